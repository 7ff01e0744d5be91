#!/usr/bin/env bash
# A long fuzz campaign of the property tests that read hostile input: scene scripts generated from
# the gr grammar and glTF structures (tests/fuzz_scenes.rs), photon-map files with valid
# checksums and single-part, multi-part and tiled EXR tiles (tests/hostile_files.rs, its fuzz_*
# properties), and the loaders' byte mutations (tests/stability_fuzz.rs). Rounds of
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
targets=(fuzz_scenes hostile_files stability_fuzz)
for t in "${targets[@]}"; do
  cargo test --release --test "$t" --no-run >/dev/null 2>&1
done
# The test binaries, run directly: one round is one binary's fuzz properties with fresh seeds.
bins=()
for t in "${targets[@]}"; do
  bins+=("$(cargo test --release --test "$t" --no-run --message-format=json 2>/dev/null |
    sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | tail -1)")
done
start=$SECONDS
log=target/fuzz-campaign
mkdir -p "$log"
rounds=0
failures=0
# One round of target $1 (index into bins) as round $2; its status in $log/$2.status.
round() {
  local bin=${bins[$1]} name=${targets[$1]} n=$2 filter=""
  [ "$name" = hostile_files ] && filter=fuzz_
  local status=0
  (
    ulimit -v $((gib * 1024 * 1024))
    PROPTEST_CASES=$cases timeout 1200 "$bin" $filter --test-threads 1 -q
  ) >"$log/$n.log" 2>&1 || status=$?
  echo "$status" >"$log/$n.status"
}
cpu_before=$(awk '{print $14 + $15 + $16 + $17}' /proc/$$/stat)
# Rounds of one target never overlap (a test binary clears its own output folders), so at most
# one round per target runs at a time: the next target in turn that is not running.
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
