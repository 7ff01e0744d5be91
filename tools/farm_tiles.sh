#!/usr/bin/env bash
# A render farm on one machine: scenes/final.lua at --scale F in 8 bands, rendered whole,
# as 8 tiles that each trace their own photon maps, and as one `caustic photons --save` and
# 8 tiles reading its file. Checks that both stitched images equal the full render byte for
# byte and prints the CPU time (user + sys) of each way (issue 18's farm figure).
#
#   bash tools/farm_tiles.sh 0.5
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
C="${CAUSTIC:-$ROOT/target/release/caustic}"
S="$ROOT/scenes/final.lua"
SC="${1:-0.5}"
D="$(mktemp -d)"
trap 'rm -rf "$D"' EXIT
cd "$D"
W=$(awk -v s="$SC" 'BEGIN { printf "%d", 1024 * s + 0.5 }')
cpu() { local f=$1; shift; /usr/bin/time -f "%U %S %e" -a -o "$D/$f.time" "$@"; }
band() { echo "0,$(($1 * W / 8)),$W,$((($1 + 1) * W / 8))"; }
cpu full "$C" render "$S" --scale "$SC" -q -o full.exr 2>/dev/null
for i in 0 1 2 3 4 5 6 7; do
  cpu own "$C" render "$S" --scale "$SC" -q --crop "$(band $i)" -o own$i.exr 2>/dev/null
done
cpu shared "$C" photons "$S" --scale "$SC" -q --save maps.bin 2>/dev/null
for i in 0 1 2 3 4 5 6 7; do
  cpu shared "$C" render "$S" --scale "$SC" -q --photon-maps maps.bin --crop "$(band $i)" -o sh$i.exr 2>/dev/null
done
"$C" stitch own?.exr -o own.exr 2>/dev/null
"$C" stitch sh?.exr -o shared.exr 2>/dev/null
cmp full.exr own.exr && echo "8 tiles with their own maps: byte-identical to the full render"
cmp full.exr shared.exr && echo "8 tiles reading maps.bin: byte-identical to the full render"
for f in full own shared; do
  awk -v n=$f '{ u += $1; s += $2; e += $3 } END { printf "%-7s %d runs  CPU %.1f s (user %.1f + sys %.1f)  wall %.1f s\n", n, NR, u + s, u, s, e }' $f.time
done
echo "maps.bin: $(stat -c %s maps.bin) bytes"
