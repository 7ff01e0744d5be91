#!/usr/bin/env bash
# Wall time of one render with 1 and 2 threads, alternating, best and median of REPS each, and
# the speed-up. Runs are alternated so that slow spells of a shared machine hit both counts.
#
#   bash tools/thread_scaling.sh SCENE.lua [caustic render options...]
#   REPS=3 bash tools/thread_scaling.sh Assets/room2.lua --scale 0.5   # from the scene's folder
#
# Environment: REPS [3], CAUSTIC [the release binary beside this script's workspace].
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
caustic="${CAUSTIC:-$here/target/release/caustic}"
reps="${REPS:-3}"
scene="$1"
shift
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
declare -A times
for ((r = 1; r <= reps; r++)); do
    for t in 1 2; do
        start=$(date +%s.%N)
        "$caustic" render "$scene" --threads "$t" -q -o "$out/t$t.png" "$@" >/dev/null 2>&1
        end=$(date +%s.%N)
        times[$t]+="$(echo "$end - $start" | bc) "
    done
    cmp -s "$out/t1.png" "$out/t2.png" || { echo "images differ between 1 and 2 threads" >&2; exit 1; }
done
stats() { tr ' ' '\n' <<<"$1" | grep . | sort -g | awk '{a[NR]=$1} END {printf "best %.2f s, median %.2f s", a[1], a[int((NR+1)/2)]}'; }
best() { tr ' ' '\n' <<<"$1" | grep . | sort -g | head -1; }
echo "scene $scene $*: $reps runs each, images identical"
echo "1 thread:  $(stats "${times[1]}")"
echo "2 threads: $(stats "${times[2]}")"
echo "speed-up (best over best): $(echo "scale=2; $(best "${times[1]}") / $(best "${times[2]}")" | bc)x"
