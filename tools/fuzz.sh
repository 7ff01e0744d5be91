#!/usr/bin/env bash
# A long fuzz campaign of the loaders' property tests (tests/stability_fuzz.rs): rounds of
# PROPTEST_CASES cases per property, each round with fresh random seeds, until SECONDS (default
# 300) have passed, under a virtual-memory limit (GiB, default 8) so a loader that trusted a size
# it read fails instead of taking the machine. Prints the rounds, the cases and the failures.
#   bash tools/fuzz.sh [SECONDS] [CASES_PER_ROUND] [GIB]
set -euo pipefail
cd "$(dirname "$0")/.."
budget=${1:-300}
cases=${2:-2000}
gib=${3:-8}
cargo test --release --test stability_fuzz --no-run >/dev/null 2>&1
start=$SECONDS
rounds=0
failures=0
while (( SECONDS - start < budget )); do
  if ! (ulimit -v $((gib * 1024 * 1024)); PROPTEST_CASES=$cases \
        cargo test --release --test stability_fuzz -q >/tmp/caustic-fuzz.log 2>&1); then
    failures=$((failures + 1))
    cp /tmp/caustic-fuzz.log "target/fuzz-failure-$rounds.log"
    echo "fuzz: round $rounds failed, see target/fuzz-failure-$rounds.log" >&2
  fi
  rounds=$((rounds + 1))
done
echo "fuzz: $rounds rounds x 6 properties x $cases cases = $((rounds * 6 * cases)) cases in $((SECONDS - start)) s, $failures failed rounds"
