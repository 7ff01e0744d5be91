#!/usr/bin/env bash
# The final scene at 1024x1024: the defaults against --time-budget set to the defaults' own wall
# time, both measured against two long renders (64 samples a pixel, 4 times the photons and the
# cache rays, seeds 1 and 2) below the ceiling light, with the difference pictures written to
# docs/images/. Prints a table row per render.
#
#   cargo build --release && bash tools/accuracy/final_budget.sh
#
# The pictures are written at 1024x1024; the committed ones are halved (2x2 box means) to keep the
# repository small.
#
# Run it on an idle machine: about 15 minutes on 2 cores (the references once, into
# target/accuracy/final_budget/).
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=target/release/caustic
OUT=target/accuracy/final_budget
mkdir -p "$OUT" docs/images
REGION=0,160,1024,1024
for seed in 1 2; do
  [ -f "$OUT/ref$seed.exr" ] && continue
  "$BIN" render scenes/final.lua --spp 64 --photon-scale 4 --cache-rays 1024 --seed "$seed" \
    -q -o "$OUT/ref$seed.exr"
done
# run NAME ARGS...: renders, then prints NAME, wall and CPU seconds and the relative RMSE.
run() {
  local name=$1; shift
  /usr/bin/time -f "%e %U %S" -o "$OUT/$name.time" "$BIN" render scenes/final.lua "$@" \
    -o "$OUT/$name.exr" 2> "$OUT/$name.log"
  local err
  err=$("$BIN" diff "$OUT/$name.exr" "$OUT/ref1.exr" --second "$OUT/ref2.exr" \
    --region "$REGION" -o "docs/images/final_error_$name.png" | awk '/relative RMSE/ {print $3}')
  awk -v n="$name" -v e="$err" '{printf "%s: %.1f s wall, %.1f s CPU, relative RMSE %s\n", n, $1, $2 + $3, e}' \
    "$OUT/$name.time"
}
run defaults -q
# The budget counts from the built scene: leave the 2 s the defaults spent reading the script
# and the 2M-triangle water mesh and building its BVH.
WALL=$(awk '{print $1 - 2}' "$OUT/defaults.time")
run budget --time-budget "$WALL"
grep -h planned "$OUT/budget.log"
