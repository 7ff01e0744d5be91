#!/usr/bin/env bash
# Adaptive pixels (--noise-target) against uniform samples per pixel, at equal CPU time, on the
# three scenes of docs/accuracy.md: for each, a study over --spp and a study over
# --noise-target from the default 4 samples (the photon passes and every other flag at their
# defaults in both), measured against the two Mitsuba references as tools/accuracy/run.sh does.
# Writes docs/accuracy/NAME/{uniform,adaptive}.{csv,md,png} and prints, for each adaptive
# setting, the uniform curve's error at the same CPU time (log-log interpolation) and the ratio.
#
#   cargo build --release && bash tools/accuracy/adaptive.sh > docs/accuracy/adaptive.md
#
# Timings: run it on an idle machine. About 10 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=target/release/caustic
OUT=target/accuracy
DOCS=docs/accuracy

# pair NAME SCENE REFS SCALE REGION TARGETS
pair() {
  local name=$1 scene=$2 refs=$3 scale=$4 region=$5 targets=$6
  local ref="$refs/$(basename "$scene" .lua).exr" second="$refs/$(basename "$scene" .lua).second.exr"
  "$BIN" study "$scene" --reference "$ref" --second "$second" --seeds 2 --region "$region" \
    --base="--scale $scale" --sweep spp=4,8,16,32 \
    --title "$name: uniform samples per pixel" -o "$OUT/$name/uniform" > /dev/null
  "$BIN" study "$scene" --reference "$ref" --second "$second" --seeds 2 --region "$region" \
    --base="--scale $scale --max-spp 256" --sweep "noise-target=$targets" \
    --compare "uniform=$OUT/$name/uniform/study.csv" \
    --title "$name: adaptive pixels" -o "$OUT/$name/adaptive" > /dev/null
  mkdir -p "$DOCS/$name"
  for kind in uniform adaptive; do
    for ext in csv md png; do cp "$OUT/$name/$kind/study.$ext" "$DOCS/$name/$kind.$ext"; done
  done
}

pair cornell_diffuse scenes/validate/cornell_diffuse.lua tools/validate/refs 1 0,8,96,96 0.2,0.1,0.05,0.025
pair glass_in_water scenes/validate/glass_in_water.lua tools/validate/refs 1 0,8,96,96 0.2,0.1,0.05,0.025
pair showcase scenes/cornell_glass.lua tools/accuracy/refs 0.25 0,16,100,100 0.2,0.1,0.05,0.025

python3 - "$DOCS" <<'PY'
import csv, math, sys
docs = sys.argv[1]

def rows(path):
    """Mean CPU seconds and relative RMSE per setting, over its seeds."""
    acc = {}
    for r in csv.DictReader(open(path)):
        a = acc.setdefault(r["setting"], [0.0, 0.0, 0])
        a[0] += float(r["cpu_s"]); a[1] += float(r["rel_rmse"]); a[2] += 1
    return [(k, a[0] / a[2], a[1] / a[2]) for k, a in acc.items()]

def at(curve, t):
    """The curve's error at CPU time t, interpolated in log-log (extrapolated at the ends)."""
    c = sorted((s, e) for _, s, e in curve)
    i = 1
    while i < len(c) - 1 and c[i][0] < t:
        i += 1
    (t0, e0), (t1, e1) = c[i - 1], c[i]
    k = math.log(e1 / e0) / math.log(t1 / t0)
    return e0 * (t / t0) ** k

print("| scene | adaptive setting | CPU s | rel. RMSE | uniform at that CPU time | ratio |")
print("|---|---|---|---|---|---|")
for name in ("cornell_diffuse", "glass_in_water", "showcase"):
    uni = rows(f"{docs}/{name}/uniform.csv")
    for setting, t, e in rows(f"{docs}/{name}/adaptive.csv"):
        u = at(uni, t)
        print(f"| {name} | {setting} | {t:.2f} | {e:.4f} | {u:.4f} | {e / u:.2f} |")
PY
