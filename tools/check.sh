#!/usr/bin/env bash
# The one gate: formatting, lints and the whole test suite, in release mode.
# People run it before committing; .ci/run runs exactly this.
set -euo pipefail
cd "$(dirname "$0")/.."

if cargo fmt --version >/dev/null 2>&1; then
  cargo fmt --all -- --check
else
  echo "check: rustfmt is not installed; skipping the format check" >&2
fi
if cargo clippy --version >/dev/null 2>&1; then
  cargo clippy --release --workspace --all-targets --locked -- -D warnings
else
  echo "check: clippy is not installed; skipping lints" >&2
fi
cargo test --release --locked
