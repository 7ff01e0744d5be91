#!/usr/bin/env bash
# Where a farm render's time goes, for the scaling model of docs/farm.md: the final scene (or
# SCENE) at its full size, as the photon pass (caustic photons --save: scene load, photon
# tracing and kd-trees, precomputation points, irradiance cache) and then N bands for N in
# 1 2 4 8, each band a process reading the maps, run one after another here (each with
# THREADS threads), and the stitch. Prints, per step, CPU and wall seconds (/usr/bin/time), and
# for each N the busiest band, the sum over bands and what loading the scene costs each band
# (a render of a 1x1 window: scene load and nothing else).
#   bash tools/farm_scaling.sh [SCENE] [THREADS]
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
scene=$root/${1:-scenes/final.lua}
threads=${2:-2}
cargo build --release --locked -q
bin=$root/target/release/caustic
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

# Runs a command; prints "cpu wall" in seconds.
timed() {
  /usr/bin/time -f "%U %S %e" "$@" 2>&1 >/dev/null | tail -1 | awk '{printf "%.2f %.2f", $1 + $2, $3}'
}

line=$(timed "$bin" photons "$scene" -q --threads "$threads" --save maps.bin)
echo "photon pass (load, trace, kd-trees, points, cache): cpu wall = $line"
echo "photon-map file: $(stat -c %s maps.bin) bytes"
# The image's size, from the error a window larger than any image gets.
said=$("$bin" render "$scene" -q --photon-maps maps.bin --crop 0,0,1000000,1000000 \
  -o probe.png 2>&1 || true)
size=$(echo "$said" | sed -n 's/.*inside the \([0-9]*\)x\([0-9]*\) image.*/\1 \2/p' | head -1)
read -r width height <<<"$size"
load=$(timed "$bin" render "$scene" -q --threads "$threads" --photon-maps maps.bin \
  --crop 0,0,1,1 -o probe.png)
echo "a 1x1 band (scene load, map read, nothing rendered): cpu wall = $load"
for n in 1 2 4 8; do
  sum_cpu=0
  worst=0
  for ((i = 0; i < n; i++)); do
    y0=$((i * height / n))
    y1=$(((i + 1) * height / n))
    t=$(timed "$bin" render "$scene" -q --threads "$threads" --photon-maps maps.bin \
      --crop "0,$y0,$width,$y1" -o "tile$i.png")
    sum_cpu=$(echo "$sum_cpu + ${t% *}" | bc)
    worst=$(echo "if (${t#* } > $worst) ${t#* } else $worst" | bc)
  done
  st=$(timed "$bin" stitch tile*.png -o stitched.png)
  echo "N=$n bands: cpu over bands $sum_cpu s; busiest band wall $worst s; stitch cpu wall = $st"
  rm -f tile*.png
done
