#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `impulse farm --submit` on a real Slurm: a single-node cluster started here under a temporary
# configuration (munged with its own key and socket; slurmctld and slurmd from one slurm.conf,
# proctrack/linuxproc, task/none, no cgroup.conf, the node's CPUs and memory from the machine).
# A 4-task array renders 40 small frames; the frames must be byte-identical to one local run and
# the video assembled by the dependent encode job must have 40 frames and be the video the local
# frames encode to. The daemons started here are always stopped (trap).
# Exit 77 (CTest's SKIP_RETURN_CODE) when the cluster cannot start, saying exactly why; then the
# test is reported skipped, never passed. Usage: test_slurm.sh IMPULSE_BINARY
set -uo pipefail

impulse=$(realpath "$1")
skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAILED: $*"; exit 1; }

# --- what this needs: found, never installed here (scripts/setup.sh installs them) ---
for tool in munged slurmctld slurmd sbatch squeue sinfo; do
    path=$(PATH="$PATH:/usr/sbin:/sbin" command -v "$tool") ||
        skip "$tool not found (scripts/setup.sh installs Debian's slurm-wlm and munge)"
    declare "bin_$tool=$path"
done
[ "$(id -u)" -eq 0 ] || skip "slurmd runs jobs as their user and must start as root (running as uid $(id -u))"

work=$(mktemp -d "${TMPDIR:-/tmp}/impulse-slurm-XXXXXX") || fail "mktemp"
chmod 700 "$work"
pids=()
cleanup() {
    for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null; done
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null
    done
    rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# Waits up to $1 seconds for the command after it to succeed; gives up at once if a daemon
# started here has exited.
wait_for() {
    local limit=$1; shift
    local end=$((SECONDS + limit))
    until "$@" >/dev/null 2>&1; do
        [ $SECONDS -lt $end ] || return 1
        for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null || return 1; done
        sleep 0.2
    done
}

# --- munged: its own key and socket ---
dd if=/dev/urandom of="$work/munge.key" bs=1024 count=1 status=none && chmod 400 "$work/munge.key"
"$bin_munged" --foreground --force --key-file="$work/munge.key" --socket="$work/munge.sock" \
    --pid-file="$work/munged.pid" --log-file="$work/munged.log" --seed-file="$work/munge.seed" \
    >"$work/munged.out" 2>&1 &
pids+=($!)
wait_for 10 test -S "$work/munge.sock" ||
    skip "munged did not start: $(tail -n 3 "$work/munged.out" "$work/munged.log" 2>/dev/null | tr '\n' ' ')"

# --- one slurm.conf for both daemons and the clients; free ports from the ephemeral-free range ---
port() { local p; while :; do p=$((20000 + RANDOM % 20000)); ! (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null && break; done; echo $p; }
host=$(hostname -s)
cpus=$(nproc)
memory_mib=$(($(awk '/^MemTotal/ {print $2}' /proc/meminfo) / 1024 * 9 / 10))
mkdir -p "$work/state" "$work/spool"
cat >"$work/slurm.conf" <<CONF
ClusterName=impulsetest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$(port)
SlurmdPort=$(port)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge.sock
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
MpiDefault=none
ReturnToService=2
KillWait=5
MinJobAge=300
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory_mib State=UNKNOWN
PartitionName=impulse Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
"$bin_slurmctld" -D -i -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
pids+=($!)
"$bin_slurmd" -D -f "$SLURM_CONF" >"$work/slurmd.out" 2>&1 &
pids+=($!)
why_not() { tail -n 4 "$work"/slurmctld.out "$work"/slurmd.out "$work"/slurmctld.log "$work"/slurmd.log 2>/dev/null | tr '\n' ' '; }
node_idle() { [ "$(sinfo -h -n "$host" -o %t 2>/dev/null)" = idle ]; }
wait_for 30 node_idle || skip "the single-node cluster did not come up (a daemon exited, or not idle in 30 s): $(why_not)"
echo "cluster up: $host, $cpus CPUs, $memory_mib MiB ($(sinfo --version))"

# --- the farm: 40 frames in 4 array tasks, then the dependent encode job ---
cat >"$work/scene.toml" <<'TOML'
[output]
size = [32, 24]
fps = 24
frames = 40
preset = "ultrafast"

[[layer]]
seed = 5
density = 12.0
lifetime = 1.0
envelope = "hann"
[layer.kernel]
type = "cosine"
radius = 4.0

[[layer.flow]]
type = "uniform"
velocity = [12.0, 4.0]

[shading]
ramp = [[0.0, "#102040"], [1.0, "#fff0c0"]]
TOML
mkdir -p "$work/farm" "$work/local"
cd "$work" || fail "cd $work"
job=$("$impulse" farm scene.toml -o 'farm/f_####.exr' --chunk 10 --submit --set 'layer.0.seed=6' \
      --video farm/scene.mp4 2>"$work/farm.err") || fail "impulse farm --submit: $(cat "$work/farm.err")"
echo "submitted: $(cat "$work/farm.err")"
[[ "$job" =~ ^[0-9]+$ ]] || fail "impulse farm printed \"$job\", expected a job id"
jobs_done() { [ -z "$(squeue -h -o %i 2>/dev/null)" ] && squeue >/dev/null 2>&1; }
wait_for 90 jobs_done || fail "jobs still queued after 90 s: $(squeue 2>&1 | tr '\n' ' ') $(why_not)"

logs() { tail -n 3 farm/slurm-*.out 2>/dev/null | tr '\n' ' '; }
"$impulse" render "$work/scene.toml" -o 'local/f_####.exr' --set 'layer.0.seed=6' -q || fail "local render"
tasks=$(ls farm/slurm-"${job}"_*.out 2>/dev/null | wc -l)
[ "$tasks" -eq 4 ] || fail "expected 4 array task logs, found $tasks: $(ls farm)"
frames=0
for f in local/f_*.exr; do
    # The same absolute scene path in both runs: the metadata (impulse:scene) is identical too.
    cmp -s "$f" "farm/${f#local/}" || fail "farm/${f#local/} differs from $f (or is missing); job logs: $(logs)"
    frames=$((frames + 1))
done
[ "$frames" -eq 40 ] || fail "local run wrote $frames frames, expected 40"
[ -f farm/scene.mp4 ] || fail "no video from the encode job; job logs: $(logs)"
video_frames=$("$impulse" analyze farm/scene.mp4 --json | grep -o '"frames":[0-9]*' | head -n 1)
[ "$video_frames" = '"frames":40' ] || fail "farm/scene.mp4: $video_frames, expected 40 frames"
"$impulse" encode 'local/f_####.exr' -o local/scene.mp4 -q || fail "local encode"
cmp -s local/scene.mp4 farm/scene.mp4 || fail "farm/scene.mp4 differs from the local frames' video"
echo "PASSED: 40 frames in 4 array tasks byte-identical to a local run; the encode job's video has 40 frames"
