#!/usr/bin/env bash
# The final scene at 512^2 (its full photon counts): the defaults (4 samples a pixel), 8
# samples, and adaptive pixels at three targets, against two 64-spp renders of other seeds
# (their noise drops out of `caustic diff --second`), with their CPU times and the error maps
# of docs/accuracy/adaptive.md. About 10 minutes on 2 cores; run it on an idle machine.
#
#   cargo build --release && bash tools/accuracy/final_adaptive.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
mkdir -p "${OUT:-target/accuracy/final}"
B=target/release/caustic
A="--scale 0.5 --photon-scale 4 -q"
$B render scenes/final.lua $A --spp 64 --seed 100 -o ${OUT:-target/accuracy/final}/ref1.exr 2>&1 | tail -1
$B render scenes/final.lua $A --spp 64 --seed 101 -o ${OUT:-target/accuracy/final}/ref2.exr 2>&1 | tail -1
for cfg in "spp4:--spp 4 --error-map ${OUT:-target/accuracy/final}/err_spp4.png" "spp8:--spp 8" "nt0.1:--noise-target 0.1 --max-spp 64" "nt0.05:--noise-target 0.05 --max-spp 64 --error-map ${OUT:-target/accuracy/final}/err_nt005.png --aa-map ${OUT:-target/accuracy/final}/rays_nt005.png" "nt0.03:--noise-target 0.03 --max-spp 64"; do
  name=${cfg%%:*}; flags=${cfg#*:}
  /usr/bin/time -f "$name cpu %U+%S wall %e" $B render scenes/final.lua $A $flags -o ${OUT:-target/accuracy/final}/$name.exr 2>&1 | grep -v "^wrote ${OUT:-target/accuracy/final}/[a-z_0-9.]*png"
  $B diff ${OUT:-target/accuracy/final}/$name.exr ${OUT:-target/accuracy/final}/ref1.exr --second ${OUT:-target/accuracy/final}/ref2.exr 2>&1 | grep -i "relative RMSE\|block" | head -2
done
