#!/usr/bin/env bash
# The time planner against the defaults and a grid search: for each scene and CPU budget B (5,
# 20, 60 s), a render with --time-budget B/2 (wall seconds on 2 cores), the defaults with --spp
# raised to take about B of CPU, and a grid of --spp and --photon-scale, each measured against
# two independent references over the image below the ceiling light (as docs/accuracy.md
# measures). Writes docs/accuracy/budget.csv; tools/accuracy/budget_report.py makes the table.
#
#   bash tools/validate/setup.sh && cargo build --release && bash tools/accuracy/budget.sh
#
# PLANNER_ONLY=1 renders only the planner's images and keeps the other rows of
# docs/accuracy/budget.csv (for a change to the planner alone: the defaults and the grid do not
# run it). Timings: run it on an idle machine. About 40 minutes on 2 cores (10 planner only).
# The final scene's references (two 256x256 renders of 64 samples a pixel at 64 times the
# preview's photons, the planner's largest effort, and 8 times its cache rays) are made once
# into target/accuracy/budget/.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=target/release/caustic
OUT=target/accuracy/budget
mkdir -p "$OUT" docs/accuracy
BUDGETS=${BUDGETS:-"5 20 60"}

# cpu CMD...: runs CMD, its stderr to $OUT/log, and prints its CPU seconds (user + system).
cpu() {
  /usr/bin/time -f "%U %S" -o "$OUT/time" "$@" > /dev/null 2> "$OUT/log"
  awk '{printf "%.2f", $1 + $2}' "$OUT/time"
}
# err IMAGE: the relative RMSE against the scene's two references in its region.
err() {
  "$BIN" diff "$1" "$REF" --second "$SECOND" --region "$REGION" | awk '/relative RMSE/ {print $3}'
}
row() { echo "$NAME,$1,$2,$3,$4,$5,$6,$7" >> "$OUT/budget.csv"; }

final_refs() {
  for seed in 1 2; do
    [ -f "$OUT/final_ref$seed.exr" ] && continue
    "$BIN" render scenes/final.lua --scale 0.25 --spp 64 --photon-scale 4 --cache-rays 2048 \
      --seed "$seed" -q -o "$OUT/final_ref$seed.exr"
  done
}

# self_refs: two long caustic renders of the scene (seeds 1 and 2: 256 samples a pixel at 64
# times its photons, the planner's largest effort, and 8 times its cache rays, the rays at that
# effort: a reference with fewer photons than the plan measured would carry its own kernel blur
# into the measure), and the planner's images measured against them
# too: the planner expects caustic's own error, and against Mitsuba every caustic image also
# carries caustic's converged difference from Mitsuba (the seed-pair column of
# docs/accuracy.md), which no plan changes.
self_refs() {
  local seed ps b
  ps=$(awk -v s="$SCALE" 'BEGIN {print 64 * s * s}')
  for seed in 1 2; do
    [ -f "$OUT/$NAME.self$seed.exr" ] && continue
    "$BIN" render "$SCRIPT" --scale "$SCALE" --spp 256 --photon-scale "$ps" --cache-rays 2048 \
      --seed "$seed" -q -o "$OUT/$NAME.self$seed.exr"
  done
  for b in $BUDGETS; do
    row "$b" self "" "" "" "$("$BIN" diff "$OUT/$NAME.b$b.exr" "$OUT/$NAME.self1.exr" \
      --second "$OUT/$NAME.self2.exr" --region "$REGION" | awk '/relative RMSE/ {print $3}')" ""
  done
}

# budgets: the planner and the defaults with more samples at each budget.
budgets() {
  local c4 c32 per fixed b wall spp c expected
  if [ -n "${PLANNER_ONLY:-}" ]; then
    for b in $BUDGETS; do planned "$b"; done
    return
  fi
  c4=$(cpu "$BIN" render "$SCRIPT" --scale "$SCALE" --spp 4 -q -o "$OUT/$NAME.d4.exr")
  row "" defaults "spp=4" 4 "$c4" "$(err "$OUT/$NAME.d4.exr")" ""
  c32=$(cpu "$BIN" render "$SCRIPT" --scale "$SCALE" --spp 32 -q -o "$OUT/$NAME.d32.exr")
  row "" defaults "spp=32" 32 "$c32" "$(err "$OUT/$NAME.d32.exr")" ""
  per=$(awk -v a="$c4" -v b="$c32" 'BEGIN {print (b - a) / 28}')
  fixed=$(awk -v a="$c4" -v p="$per" 'BEGIN {print a - 4 * p}')
  for b in $BUDGETS; do
    planned "$b"
    spp=$(awk -v b="$b" -v f="$fixed" -v p="$per" 'BEGIN {s = int((b - f) / p + 0.5); print (s < 1 ? 1 : s)}')
    c=$(cpu "$BIN" render "$SCRIPT" --scale "$SCALE" --spp "$spp" -q -o "$OUT/$NAME.s$b.exr")
    # A fit from 4 and 32 samples missed larger budgets by up to 28% of their CPU (the samples'
    # cost a sample falls as they share): outside 10% of B, once more with the samples scaled
    # by the time this render's samples took.
    again=$(awk -v b="$b" -v c="$c" -v f="$fixed" -v s="$spp" 'BEGIN {
      if (s > 1 && (c > 1.1 * b || c < 0.9 * b) && c > f) { n = int(s * (b - f) / (c - f) + 0.5); print (n < 1 ? 1 : n) } }')
    if [ -n "$again" ] && [ "$again" != "$spp" ]; then
      spp=$again
      c=$(cpu "$BIN" render "$SCRIPT" --scale "$SCALE" --spp "$spp" -q -o "$OUT/$NAME.s$b.exr")
    fi
    row "$b" defaults "spp=$spp" "$spp" "$c" "$(err "$OUT/$NAME.s$b.exr")" ""
  done
}

# planned B: the planner's render with B/2 wall seconds (B CPU seconds on 2 cores).
planned() {
  local wall c expected spp setting
  wall=$(awk -v b="$1" 'BEGIN {print b / 2}')
  c=$(cpu "$BIN" render "$SCRIPT" --scale "$SCALE" --time-budget "$wall" -o "$OUT/$NAME.b$1.exr")
  expected=$(grep -o 'expected relative RMSE [0-9.]*' "$OUT/log" | awk '{print $4}')
  # Adaptive rounds: the samples a pixel the plan expected on average, after a "~".
  spp=$(grep -o ': [0-9]* spp' "$OUT/log" | awk '{print $2}')
  setting=$(grep -o 'effort x[0-9.]*' "$OUT/log")
  if grep -q 'then rounds' "$OUT/log"; then
    spp="~$(grep -o '[0-9.]* spp a pixel expected' "$OUT/log" | awk '{printf "%.1f", $1}')"
    setting="$setting; rounds from $(grep -o ': [0-9]* spp' "$OUT/log" | awk '{print $2}')"
  fi
  row "$1" budget "$setting" "$spp" "$c" "$(err "$OUT/$NAME.b$1.exr")" "$expected"
}

# grid "SPPS" "PHOTON_SCALES": every pair, one seed.
grid() {
  [ -n "${PLANNER_ONLY:-}" ] && return
  local spp ps c
  for spp in $1; do
    for ps in $2; do
      c=$(cpu "$BIN" render "$SCRIPT" --scale "$SCALE" --spp "$spp" --photon-scale "$ps" -q \
        -o "$OUT/$NAME.g.exr")
      row "" grid "spp=$spp photon-scale=$ps" "$spp" "$c" "$(err "$OUT/$NAME.g.exr")" ""
    done
  done
}

echo "scene,budget_cpu,kind,setting,spp,cpu,rel_rmse,expected" > "$OUT/budget.csv"
V=tools/validate/refs
A=tools/accuracy/refs
ONLY=${ONLY:-}
want() { [ -z "$ONLY" ] || [ "$ONLY" = "$1" ]; }
if want cornell_diffuse; then
  NAME=cornell_diffuse SCRIPT=scenes/validate/cornell_diffuse.lua SCALE=1 REGION=0,8,96,96
  REF=$V/cornell_diffuse.exr SECOND=$V/cornell_diffuse.second.exr
  budgets; grid "4 16 64 256" "0.25 1 4"; self_refs
fi
if want glass_in_water; then
  NAME=glass_in_water SCRIPT=scenes/validate/glass_in_water.lua SCALE=1 REGION=0,8,96,96
  REF=$V/glass_in_water.exr SECOND=$V/glass_in_water.second.exr
  budgets; grid "4 16 64" "0.25 1 4"; self_refs
fi
if want showcase; then
  NAME=showcase SCRIPT=scenes/cornell_glass.lua SCALE=0.25 REGION=0,16,100,100
  REF=$A/cornell_glass.exr SECOND=$A/cornell_glass.second.exr
  budgets; grid "4 16 64 256" "0.015625 0.0625 0.25"; self_refs
fi
if want final; then
  final_refs
  NAME=final SCRIPT=scenes/final.lua SCALE=0.25 REGION=0,40,256,256
  REF=$OUT/final_ref1.exr SECOND=$OUT/final_ref2.exr
  budgets; grid "4 16 48" "0.015625 0.0625 0.25"
fi
if [ -n "${PLANNER_ONLY:-}" ]; then
  grep -v ',budget,\|,self,' docs/accuracy/budget.csv | tail -n +2 >> "$OUT/budget.csv"
fi
cp "$OUT/budget.csv" docs/accuracy/budget.csv
python3 tools/accuracy/budget_report.py docs/accuracy/budget.csv
