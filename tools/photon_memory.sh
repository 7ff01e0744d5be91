#!/usr/bin/env bash
# Peak resident memory per stored photon: the course's room2.lua at 128x128 with
# --photons N --caustic-photons N, one line per binary and N (issue 18's first figure).
#
#   bash tools/photon_memory.sh 140000 1400000 7000000     # 10^6, 10^7, 5*10^7 stored
#   BINS="/path/to/old/caustic target/release/caustic" bash tools/photon_memory.sh 1400000
#
# BINS (default: this checkout's release binary) are run in turn for each N, so that a slow
# spell of a shared machine hits them alike. Needs ../shared/corpus beside the checkout.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PROJECT="$ROOT/../shared/corpus/cs488/tengyucai__Computer-Graphics/Project"
[ -d "$PROJECT" ] || { echo "no corpus at $PROJECT" >&2; exit 1; }
BINS="${BINS:-$ROOT/target/release/caustic}"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
cd "$PROJECT"
for n in "$@"; do
  for b in $BINS; do
    log=$("$b" render Assets/room2.lua --scale 0.125 --photons "$n" --caustic-photons "$n" --stats -q -o "$OUT/x.exr" 2>&1)
    stored() { echo "$log" | sed -n "s/.*$1 map: [0-9]* photons emitted, \([0-9]*\) stored.*/\1/p"; }
    peak=$(echo "$log" | sed -n 's/.*peak resident memory: \([0-9.]*\) MiB/\1/p')
    wall=$(echo "$log" | sed -n 's/^wrote .* in \(.*\) s$/\1/p')
    awk -v b="$b" -v n="$n" -v g="$(stored global)" -v c="$(stored caustic)" -v p="$peak" -v w="$wall" \
      'BEGIN { s = g + c; printf "%s N=%s stored %d peak %.1f MiB = %.1f B/photon, wall %s s\n", b, n, s, p, p * 1048576 / s, w }'
  done
done
