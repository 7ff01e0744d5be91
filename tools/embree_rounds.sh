#!/usr/bin/env bash
# caustic's single-ray traversal against Embree 3 on the wave mesh, in alternating rounds: each
# round runs one engine, then the other (the order swapped every round), and the table gives
# each engine's median and range over the rounds and the median of the per-round ratios. A
# shared VM's speed drifts by 10-30% within minutes (seen on two hosts), so one run of each, as
# `../shared/bench/run.sh` takes them minutes apart, can put either engine ahead; a ratio taken
# inside one round, seconds apart, and its median over rounds does not move with the drift.
# One engine runs at a time: two at once share the L3 cache and the memory bus, which this
# memory-bound workload feels.
#
#   bash tools/embree_rounds.sh                  # 8 rounds, 2M-triangle mesh (N = 1001)
#   ROUNDS=12 REPS=3 bash tools/embree_rounds.sh
#   CAUSTIC_BENCH=/tmp/old/bench_traversal bash tools/embree_rounds.sh   # another build
#
# Environment (defaults in brackets):
#   ROUNDS         rounds                                            [8]
#   REPS           timed passes per query and round (+1 warm-up)     [5]
#   N              wave mesh grid size (N x N vertices, 2(N-1)^2 triangles) [1001]
#   QUALITY        Embree build quality                              [medium]
#   ISA            Embree's kernels (avx2, avx512, sse4.2 ...)       [Embree's choice: the widest]
#   MODES          Embree's query modes (1, 4, 8, 16, 1M): 1 single rays, 1M streams, the
#                  others packets; caustic has single rays and streams [1,1M]
#   BENCH          the harness's folder                  [../shared/bench beside the checkout]
#   DATA_DIR       where run.sh keeps its binaries, mesh and rays; what is missing is made
#                  there with run.sh's commands                      [/tmp/embree_bench]
#   CAUSTIC_BENCH  the bench_traversal binary       [target/release/bench_traversal]
# Needs libembree-dev (Embree 3) and gcc, as run.sh does. Rates are Mrays/s of the fastest pass
# by the tracing thread's CPU time, as in run.sh's table.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
rounds="${ROUNDS:-8}"
reps="${REPS:-5}"
n="${N:-1001}"
quality="${QUALITY:-medium}"
isa="${ISA:-}"
modes="${MODES:-1,1M}"
bench="${BENCH:-$here/../shared/bench}"
data="${DATA_DIR:-/tmp/embree_bench}"
ours="${CAUSTIC_BENCH:-$here/target/release/bench_traversal}"

case "$modes" in *[!0-9M,]* | "") echo "MODES is a comma list of 1, 4, 8, 16, 1M" >&2; exit 2 ;; esac
case "$rounds$reps$n" in *[!0-9]*) echo "ROUNDS, REPS and N must be whole numbers" >&2; exit 2 ;; esac
if ((rounds < 1 || rounds > 100 || reps < 1 || reps > 100 || n < 2 || n > 4001)); then
  echo "ROUNDS and REPS must be 1 to 100, N 2 to 4001" >&2
  exit 2
fi
[ -x "$ours" ] || { echo "no $ours: cargo build --release -p caustic-tools --bin bench_traversal" >&2; exit 1; }
[ -f "$bench/embree_bench.c" ] || { echo "no Embree harness at $bench (set BENCH)" >&2; exit 1; }
[ -f /usr/include/embree3/rtcore.h ] ||
  { echo "libembree-dev (Embree 3) is missing: apt-get install -y libembree-dev" >&2; exit 1; }

mkdir -p "$data/bin"
[ -x "$data/bin/gen" ] || gcc -O2 -Wall -o "$data/bin/gen" "$bench/gen.c" -lm
[ -x "$data/bin/embree_bench" ] ||
  gcc -O3 -march=native -Wall -o "$data/bin/embree_bench" "$bench/embree_bench.c" -lembree3 -lm -lpthread
mesh="$data/wave_N$n.mesh"
primary="$data/primary_1024x1024.rays"
incoherent="$data/incoherent_1048576_s12345.rays"
[ -f "$mesh" ] || "$data/bin/gen" mesh "$n" "$mesh"
[ -f "$primary" ] || "$data/bin/gen" primary 1024 1024 "$primary"
[ -f "$incoherent" ] || "$data/bin/gen" incoherent 1048576 12345 "$incoherent"

logs="$(mktemp -d)"
trap 'rm -rf "$logs"' EXIT
run_embree() {
  "$data/bin/embree_bench" --quality "$quality" ${isa:+--isa "$isa"} --modes "$modes" --reps "$reps" \
    --build-reps 1 --threads 1 "$mesh" "$incoherent" "$primary"
}
run_ours() {
  "$ours" --mt 0 --reps "$reps" --build-reps 1 --verify 0 "$mesh" "$incoherent" "$primary"
}
# One line per round, engine and query: round engine kind mode rate.
for ((r = 1; r <= rounds; r++)); do
  if ((r % 2)); then order="embree caustic"; else order="caustic embree"; fi
  for e in $order; do
    if [ "$e" = embree ]; then run_embree; else run_ours; fi >"$logs/out" 2>&1 ||
      { cat "$logs/out" >&2; echo "$e failed in round $r" >&2; exit 1; }
    awk -v r="$r" -v e="$e" '/^TRACE/ {
        for (i = 2; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
        print r, e, v["kind"], v["mode"], v["mrays_cpu_best"]
      }' "$logs/out" >>"$logs/rates"
  done
  echo "round $r of $rounds done" >&2
done

echo "caustic ($(basename "$ours")) against Embree 3 $quality${isa:+ ($isa kernels)}, wave mesh N = $n, $rounds alternating rounds of $reps passes"
echo
echo "| rays | query | Embree Mrays/s, median [min-max] | caustic | caustic / Embree per round, median [min-max] | rounds caustic ahead |"
echo "|---|---|---:|---:|---:|---:|"
sort -k3,3 -k4,4 -k1,1n "$logs/rates" | awk '
  function med(a, k,   i, j, t) {   # sorts a[1..k] in place and returns its median
    for (i = 2; i <= k; i++) { t = a[i]; for (j = i - 1; j >= 1 && a[j] > t; j--) a[j + 1] = a[j]; a[j + 1] = t }
    return k % 2 ? a[(k + 1) / 2] : (a[k / 2] + a[k / 2 + 1]) / 2
  }
  function query(m,   w) {          # intersect1 -> closest, occluded1M -> shadow, stream ...
    w = m; sub(/^(intersect|occluded)/, "", w)
    return (m ~ /^intersect/ ? "closest" : "shadow") \
      (w == "1M" ? ", stream" : w == "1" ? "" : ", packets of " w)
  }
  function flush(   k, ne, nc, nr, ahead, ke, kc) {
    if (key == "") return
    ne = nc = nr = ahead = 0
    for (k = 1; k <= maxr; k++) {
      if ((k, "embree") in rate) e[++ne] = rate[k, "embree"]
      if ((k, "caustic") in rate) c[++nc] = rate[k, "caustic"]
      if ((k, "embree") in rate && (k, "caustic") in rate) {
        q[++nr] = rate[k, "caustic"] / rate[k, "embree"]; ahead += q[nr] >= 1
      }
    }
    split(key, kk, SUBSEP)
    if (ne == 0 || nc == 0) {      # a mode only one engine has (Embree packets)
      if (ne) printf "| %s | %s | %.2f [%.2f-%.2f] | - | - | - |\n", kk[1], query(kk[2]),
        med(e, ne), e[1], e[ne]
      if (nc) printf "| %s | %s | - | %.2f [%.2f-%.2f] | - | - |\n", kk[1], query(kk[2]),
        med(c, nc), c[1], c[nc]
      delete rate; delete e; delete c; delete q; maxr = 0
      return
    }
    ke = med(e, ne); kc = med(c, nc)
    printf "| %s | %s | %.2f [%.2f-%.2f] | %.2f [%.2f-%.2f] | **%.2fx** [%.2f-%.2f] | %d of %d |\n",
      kk[1], query(kk[2]), ke, e[1], e[ne], kc, c[1], c[nc],
      med(q, nr), q[1], q[nr], ahead, nr
    delete rate; delete e; delete c; delete q; maxr = 0
  }
  { k = $3 SUBSEP $4; if (k != key) { flush(); key = k }
    rate[$1, $2] = $5; if ($1 > maxr) maxr = $1 }
  END { flush() }'
