#!/usr/bin/env bash
# The one gate: formatting, lints and the whole test suite, in release mode.
# People run it before committing; .ci/run runs exactly this. On a fresh machine it first adds
# what the gate needs and the toolchain may lack (rustfmt and clippy, through rustup), and
# names what it cannot add itself (a C compiler: Rust's linker on Linux, and the build of the
# vendored Lua).
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v "${CC:-cc}" >/dev/null 2>&1; then
  echo "check: no C compiler (${CC:-cc}) on PATH; Rust links with it and mlua builds its" \
    "vendored Lua with it: install one (Debian/Ubuntu: apt install build-essential)" >&2
  exit 1
fi

for tool in fmt clippy; do
  if ! cargo "$tool" --version >/dev/null 2>&1; then
    component=$([ "$tool" = fmt ] && echo rustfmt || echo clippy)
    if ! command -v rustup >/dev/null 2>&1; then
      echo "check: cargo $tool is missing and there is no rustup to add it; install $component" \
        "with the toolchain (https://rustup.rs, or your distribution's $component package)" >&2
      exit 1
    fi
    echo "check: installing $component" >&2
    rustup component add "$component"
  fi
done
cargo fmt --all -- --check
cargo clippy --release --workspace --all-targets --locked -- -D warnings
cargo test --release --locked
