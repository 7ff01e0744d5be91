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
# One line per run: threads and wall seconds.
for ((r = 1; r <= reps; r++)); do
    for t in 1 2; do
        start=$(date +%s%N)
        "$caustic" render "$scene" --threads "$t" -q -o "$out/t$t.png" "$@" >/dev/null 2>&1
        echo "$t $(( $(date +%s%N) - start ))" >>"$out/times"
    done
    cmp -s "$out/t1.png" "$out/t2.png" || { echo "images differ between 1 and 2 threads" >&2; exit 1; }
done
echo "scene $scene $*: $reps runs each, images identical"
sort -k1,1n -k2,2n "$out/times" | awk '
    { s[$1, ++n[$1]] = $2 / 1e9 }
    END {
        for (t = 1; t <= 2; t++)
            printf "%d thread(s): best %.2f s, median %.2f s\n", t, s[t, 1], s[t, int((n[t] + 1) / 2)]
        printf "speed-up (best over best): %.2fx\n", s[1, 1] / s[2, 1]
    }'
