#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Calibration of the stationarity verdict of `impulse analyze` (issue 18): render N seeds of a
# scene in a small window, analyse each sequence against the scene's theory (--scene) and count
# the verdicts. The README's figures come from this script.
#
# Usage: scripts/calibrate_stationarity.sh [--impulse PATH] [--seeds N] [--first-seed S]
#                                          [--crop WxH] [--frames A-B] [--no-scene] SCENE
#                                          [--set key=value]...
# e.g.   scripts/calibrate_stationarity.sh --seeds 24 --crop 192x192 --frames 0-239 drift
# Prints one line per seed (seed, verdict, the three tests' statistics) and the counts. Frames go
# to a temporary directory that is removed at the end. --first-seed S runs seeds S .. S + N - 1
# (to split the seeds over several runs).
set -euo pipefail

impulse=impulse seeds=24 first=1 crop=192x192 frames=0-239 use_scene=1
while [[ $# -gt 0 ]]; do
    case "$1" in
        --impulse) impulse=$2; shift 2 ;;
        --seeds) seeds=$2; shift 2 ;;
        --first-seed) first=$2; shift 2 ;;
        --crop) crop=$2; shift 2 ;;
        --frames) frames=$2; shift 2 ;;
        --no-scene) use_scene=0; shift ;;
        *) break ;;
    esac
done
[[ $# -ge 1 ]] || { echo "usage: $0 [--impulse PATH] [--seeds N] [--first-seed S] [--crop WxH] [--frames A-B] [--no-scene] SCENE [--set k=v]..." >&2; exit 2; }
scene=$1; shift
sets=("$@")

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
declare -A count=()
for ((seed = first; seed < first + seeds; ++seed)); do
    rm -f "$tmp"/f_*.exr
    "$impulse" render "$scene" --crop "$crop" --seed "$seed" --frames "$frames" -q \
        -o "$tmp/f_####.exr" "${sets[@]}"
    args=("$tmp/f_####.exr" --json "$tmp/a.json")
    if [[ $use_scene == 1 ]]; then
        args+=(--scene "$scene" --set "output.size=[${crop/x/,}]" --set "seed=$seed")
        for s in "${sets[@]}"; do [[ $s == --set ]] || args+=(--set "$s"); done
    fi
    "$impulse" analyze "${args[@]}" > /dev/null
    line=$(/usr/bin/python3 - "$tmp/a.json" "$seed" <<'PY'
import json, sys
st = json.load(open(sys.argv[1]))["stationarity"]
lv, sd = st.get("level", {}), st.get("spectral_drift", {})
print(sys.argv[2], st["verdict"],
      "z_trend=%.3g/%.3g z_blocks=%.3g/%.3g spectral=%.3g/%.3g detectable=%.3g block_dof=%.3g" % (
          lv.get("z_trend", 0), lv.get("z_trend_limit", 0), lv.get("z_blocks", 0),
          lv.get("z_blocks_limit", 0), sd.get("max_abs_z_corrected", 0), sd.get("threshold", 0),
          st.get("detectable_drift", 0), lv.get("block_dof", 0)))
PY
)
    echo "$line"
    v=$(echo "$line" | cut -d' ' -f2- | sed 's/ z_trend=.*//')
    count[$v]=$(( ${count[$v]:-0} + 1 ))
done
echo "--- $scene, $seeds seeds, $crop, frames $frames:"
for v in "${!count[@]}"; do echo "$v: ${count[$v]}"; done
