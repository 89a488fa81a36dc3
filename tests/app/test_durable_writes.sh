#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# Durable writes (docs/design.md §4): every file impulse writes (a frame of a sequence, one image,
# a video, a volume) is flushed to the disk before it is renamed into place, and its folder is
# flushed after the rename, so a crash or a power cut leaves the old file or the new one. Checked
# on the system calls themselves, traced with strace: for each rename(TEMP, TARGET) there must be
# an fsync of TEMP before it and an fsync of TARGET's folder after it. Exit 77 (skipped) when
# strace is missing or cannot trace here. Shown able to fail: with the fsync calls of
# output/files.cpp removed every output below is reported.
set -u
impulse=$(realpath "${1:?usage: test_durable_writes.sh IMPULSE}")
command -v strace >/dev/null || { echo "skipped: strace not installed (Debian package strace)"; exit 77; }
strace -f -o /dev/null true 2>/dev/null || { echo "skipped: strace cannot trace here"; exit 77; }
# LeakSanitizer stops a process it finds traced (it traces the process itself to scan for leaks):
# under scripts/sanitize.sh the traced runs check memory errors and UB but not leaks, which the
# rest of the suite checks untraced.
[ -z "${ASAN_OPTIONS:-}" ] || export ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cd "$dir" || exit 1
fail=0

# check LOG TARGET...: each TARGET renamed into place between an fsync of its temporary and an
# fsync of its folder (strace -y prints each descriptor's path).
check() {
    local log=$1; shift
    local target
    for target in "$@"; do
        python3 - "$log" "$dir/$target" <<'PY' || fail=1
import re, sys, os
log, target = sys.argv[1], sys.argv[2]
calls = [l for l in open(log) if "fsync(" in l or "rename" in l]
renames = [i for i, l in enumerate(calls)
           if re.search(r'rename\w*\(.*"([^"]*)"\) = 0', l) and l.rstrip().split('"')[-2].endswith(os.path.basename(target))]
if not renames:
    sys.exit(f"{target}: no rename into place traced")
i = renames[-1]
temp = os.path.basename(re.findall(r'"([^"]*)"', calls[i])[0])  # rename(TEMP, TARGET)
folder = os.path.dirname(target)
synced_before = any(f"fsync(" in l and temp in l and "= 0" in l for l in calls[:i])
synced_after = any(re.search(r'fsync\(\d+<' + re.escape(folder) + r'>\)\s+= 0', l) for l in calls[i + 1:])
if not synced_before: print(f"{target}: {temp} not flushed (fsync) before the rename")
if not synced_after: print(f"{target}: folder {folder} not flushed (fsync) after the rename")
sys.exit(0 if synced_before and synced_after else 1)
PY
    done
}

trace() {  # trace LOG ARGS...: runs impulse ARGS under strace into LOG
    local log=$1; shift
    strace -f -y -qq -e trace=fsync,rename,renameat,renameat2 -o "$log" "$impulse" "$@" >/dev/null 2>&1 \
        || { echo "impulse $*: failed"; fail=1; }
}

trace seq.log render drift -q --size 32x24 --frames 0-1 -o "$dir/f_####.png"
check seq.log f_0000.png f_0001.png
trace exr.log render drift -q --size 32x24 --frames 0-0 -o "$dir/one.exr"
check exr.log one.exr
trace mp4.log render drift -q --size 32x24 --frames 0-3 -o "$dir/clip.mp4"
check mp4.log clip.mp4
trace vdb.log render cloudvolume -q --frames 0-0 --set 'volume.size=[8,8,8]' -o "$dir/cloud.vdb"
check vdb.log cloud.vdb

[ "$fail" -eq 0 ] && echo "every output flushed before its rename and its folder after it"
exit "$fail"
