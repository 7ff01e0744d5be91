#!/usr/bin/env bash
# Regenerates docs/accuracy.md and its plots: for each scene, Mitsuba 3's path tracer's error
# against time, a study of the progressive integrator over passes, and a study of the photon
# mapper over photon counts and final-gather rays with both curves drawn beside it.
#
#   bash tools/validate/setup.sh && cargo build --release && bash tools/accuracy/run.sh
#
# Timings: run it on an idle machine (nothing else building or rendering). About 20 minutes
# on 2 cores. Scratch images go to target/accuracy/; the tables, CSVs and plots to docs/accuracy/.
set -euo pipefail
cd "$(dirname "$0")/../.."
PY=tools/validate/.venv/bin/python
BIN=target/release/caustic
OUT=target/accuracy
DOCS=docs/accuracy
mkdir -p "$OUT" "$DOCS"

# study NAME SCENE REFS SCALE REGION PM_SWEEPS PROGRESSIVE_BASE
# REGION leaves out the rows that show the ceiling light: its edges alias at a few camera
# samples per pixel, which a 1024-spp path tracer averages away, and would drown everything else.
study() {
  [ -n "${ONLY:-}" ] && [ "$ONLY" != "$1" ] && return 0
  local name=$1 scene=$2 refs=$3 scale=$4 region=$5 pm=$6 prog=$7
  local ref="$refs/$(basename "$scene" .lua).exr" second="$refs/$(basename "$scene" .lua).second.exr"
  "$PY" tools/accuracy/mitsuba_curve.py "$scene" "$OUT/$name/mitsuba" --scale "$scale" \
    --region "$region" --refs "$refs" --spp 4,16,64,256,1024 --ref-spp "${REF_SPP:-4096}"
  "$BIN" study "$scene" --reference "$ref" --second "$second" --seeds 2 --region "$region" \
    --base="--scale $scale --integrator progressive $prog" --sweep passes=4,16,64 \
    --title "$name: progressive photon mapping" -o "$OUT/$name/progressive" > /dev/null
  # shellcheck disable=SC2086
  "$BIN" study "$scene" --reference "$ref" --second "$second" --seeds 2 --region "$region" \
    --base="--scale $scale" $pm \
    --compare "progressive=$OUT/$name/progressive/study.csv" \
    --compare "Mitsuba 3 path tracer=$OUT/$name/mitsuba/mitsuba.csv" \
    --title "$name: photon mapping" -o "$OUT/$name/photon_map" > /dev/null
  mkdir -p "$DOCS/$name"
  for kind in photon_map progressive; do
    cp "$OUT/$name/$kind/study.csv" "$DOCS/$name/$kind.csv"
    cp "$OUT/$name/$kind/study.png" "$DOCS/$name/$kind.png"
    cp "$OUT/$name/$kind/study.md" "$DOCS/$name/$kind.md"
  done
  cp "$OUT/$name/mitsuba/mitsuba.csv" "$DOCS/$name/mitsuba.csv"
  # --target-error: where the progressive integrator stops, and the error it really has there
  # (whole image, as its estimate is).
  "$BIN" render "$scene" --scale "$scale" --integrator progressive $prog --target-error "$TARGET" \
    -q -o "$OUT/$name/target.exr" 2> "$OUT/$name/target.log"
  local line actual
  line=$(grep '^progressive:' "$OUT/$name/target.log")
  actual=$("$BIN" diff "$OUT/$name/target.exr" "$ref" --second "$second" | awk '/relative RMSE/ {print $3}')
  echo "target,passes,seconds,estimated,actual" > "$DOCS/$name/target.csv"
  echo "$line" | awk -v t="$TARGET" -v a="$actual" \
    '{for (i = 1; i <= NF; i++) { if ($(i+1) == "passes") p = $i; if ($i == "in") s = $(i+1) }
      print t "," p "," s "," $NF "," a}' >> "$DOCS/$name/target.csv"
}
TARGET=0.15

study cornell_diffuse scenes/validate/cornell_diffuse.lua tools/validate/refs 1 0,8,96,96 \
  "--sweep spp=4,16,32 --sweep photons=5e4,4e5" ""
study glass_in_water scenes/validate/glass_in_water.lua tools/validate/refs 1 0,8,96,96 \
  "--sweep spp=4,16,32 --sweep caustic-photons=2e5,2e6" ""
REF_SPP=2048 study showcase scenes/cornell_glass.lua tools/accuracy/refs 0.25 0,16,100,100 \
  "--sweep spp=4,16,32 --sweep photon-scale=0.0625,1" "--photon-scale 0.1"
"$PY" tools/accuracy/report.py "$DOCS" > docs/accuracy.md
echo "wrote docs/accuracy.md"
