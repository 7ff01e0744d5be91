#!/usr/bin/env bash
# A long fuzz campaign of the property tests that read hostile input: scene scripts generated from
# the gr grammar and glTF structures (tests/lua/script_fuzz.rs), photon-map files with valid
# checksums and single-part, multi-part and tiled EXR tiles (tests/files/hostile.rs, its fuzz_*
# properties), and the loaders' byte mutations (tests/files/loader_fuzz.rs). Rounds of
# CASES cases per property, each round with fresh random seeds, JOBS rounds at a time (never two
# of one target), until
# SECONDS (default 300) of wall time have passed. Each round runs under a virtual-memory limit
# (GiB, default 8), so a loader that trusted a size it read fails instead of taking the
# machine, and under a time limit of 20 minutes per round, so a hang fails too. Prints the
# rounds, the cases, the CPU seconds used and the failures (logs under target/).
#   bash tools/fuzz.sh [SECONDS] [CASES_PER_ROUND] [GIB] [JOBS]
set -euo pipefail
cd "$(dirname "$0")/.."
budget=${1:-300}
cases=${2:-500}
gib=${3:-8}
jobs=${4:-2}
# Each target: a name, the test binary (tests/NAME/main.rs) holding its properties, and the
# filter that picks exactly them (a test's name is its module path in the binary).
targets=(script_fuzz hostile loader_fuzz)
binaries=(lua files files)
filters=(script_fuzz:: hostile::fuzz_ loader_fuzz::)
for b in lua files; do
  cargo test --release --test "$b" --no-run >/dev/null 2>&1
done
# The test binaries, run directly: one round is one target's fuzz properties with fresh seeds.
bins=()
for b in "${binaries[@]}"; do
  bins+=("$(cargo test --release --test "$b" --no-run --message-format=json 2>/dev/null |
    sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | tail -1)")
done
start=$SECONDS
log=target/fuzz-campaign
mkdir -p "$log"
rounds=0
failures=0
# One round of target $1 (index into bins) as round $2; its status in $log/$2.status.
round() {
  local bin=${bins[$1]} filter=${filters[$1]} n=$2
  local status=0
  (
    ulimit -v $((gib * 1024 * 1024))
    PROPTEST_CASES=$cases timeout 1200 "$bin" $filter --test-threads 1 -q
  ) >"$log/$n.log" 2>&1 || status=$?
  # A filter that matches no test (a module renamed) must not pass for a clean round.
  if [ "$status" = 0 ] && grep -q '^test result: ok\. 0 passed' "$log/$n.log"; then
    status=no-tests
  fi
  echo "$status" >"$log/$n.status"
}
cpu_before=$(awk '{print $14 + $15 + $16 + $17}' /proc/$$/stat)
# Rounds of one target never overlap (its tests clear their own output folders, which no other
# target's tests use), so at most one round per target runs at a time: the next target in turn
# that is not running.
declare -A running=()
declare -a target_of=()
next=0
while (( SECONDS - start < budget )); do
  for ((k = 0; k < ${#targets[@]} && ${#running[@]} < jobs; k++)); do
    t=$(( (next + k) % ${#targets[@]} ))
    [ -n "${running[$t]:-}" ] && continue
    round "$t" "$rounds" &
    running[$t]=$!
    target_of[$rounds]=$t
    rounds=$((rounds + 1))
    next=$(( (t + 1) % ${#targets[@]} ))
  done
  wait -n || true
  for t in "${!running[@]}"; do
    kill -0 "${running[$t]}" 2>/dev/null || unset "running[$t]"
  done
done
wait
for ((n = 0; n < rounds; n++)); do
  if [ "$(cat "$log/$n.status" 2>/dev/null)" != 0 ]; then
    failures=$((failures + 1))
    echo "fuzz: round $n (${targets[${target_of[$n]}]}) failed, see $log/$n.log" >&2
  fi
done
cpu=$(awk -v t="$(getconf CLK_TCK)" '{printf "%.0f", ($14 + $15 + $16 + $17) / t}' /proc/$$/stat)
before=$(awk -v t="$(getconf CLK_TCK)" -v b="$cpu_before" 'BEGIN {printf "%.0f", b / t}')
echo "fuzz: $rounds rounds of ${targets[*]} x $cases cases per property in $((SECONDS - start)) s" \
  "of wall time and $((cpu - before)) s of CPU, under ${gib} GiB; $failures failed rounds"
