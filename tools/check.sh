#!/usr/bin/env bash
# The one gate: formatting, lints, the library's docs and the whole test suite, in release mode.
# People run it before committing; .ci/run runs exactly this. On a fresh machine it first adds
# what the gate needs and the machine may lack, and says what it adds:
# - a C compiler (Rust links with it; mlua builds its vendored Lua with it): build-essential
#   through apt-get, as root or with passwordless sudo;
# - rustup when there is neither cargo nor rustup: the distribution's rustup package through
#   apt-get where it has one (Debian 13, Ubuntu 24.04), else rustup's own installer
#   (https://sh.rustup.rs, through curl, which apt-get adds if it must), into CARGO_HOME;
# - a Rust toolchain when rustup is there but no toolchain is, and a toolchain older than the
#   crate's rust-version is updated through rustup;
# - rustfmt and clippy, through rustup.
# What it cannot add (no apt-get, no rights, no rustup) it names, with how to add it, and
# stops before building anything.
set -euo pipefail
cd "$(dirname "$0")/.."

say() { echo "check: $*" >&2; }

# Runs a command as root: directly, or through passwordless sudo; fails when neither can.
as_root() {
  if [ "$(id -u)" = 0 ]; then
    "$@"
  elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    sudo -n "$@"
  else
    return 1
  fi
}

if ! command -v "${CC:-cc}" >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1 && as_root true; then
    say "no C compiler (${CC:-cc}); installing build-essential"
    as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq build-essential >/dev/null
  fi
  if ! command -v "${CC:-cc}" >/dev/null 2>&1; then
    say "no C compiler (${CC:-cc}) on PATH; Rust links with it and mlua builds its vendored" \
      "Lua with it: install one (Debian/Ubuntu: apt install build-essential)"
    exit 1
  fi
fi

# The crate's minimum Rust (Cargo.toml's rust-version).
need=$(sed -n 's/^rust-version = "\([0-9.]*\)"/\1/p' Cargo.toml)

# Where rustup's installer puts cargo and rustup; on PATH whether or not they are there yet.
cargo_bin="${CARGO_HOME:-${HOME:-}/.cargo}/bin"
export PATH="$cargo_bin:$PATH"
# Neither cargo nor rustup: add rustup (the toolchain itself is added below).
if ! cargo --version >/dev/null 2>&1 && ! command -v rustup >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1 && as_root true &&
    as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq &&
    [ -n "$(apt-cache policy rustup 2>/dev/null | sed -n 's/^ *Candidate: \([^(].*\)/\1/p')" ]; then
    say "no Rust; installing the distribution's rustup"
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq rustup >/dev/null || true
  fi
  if ! command -v rustup >/dev/null 2>&1; then
    if ! command -v curl >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1 && as_root true; then
      say "no curl to fetch rustup with; installing curl"
      as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq curl ca-certificates \
        >/dev/null || true
    fi
    if command -v curl >/dev/null 2>&1; then
      say "no Rust; installing rustup from https://sh.rustup.rs into $cargo_bin"
      curl --proto '=https' --tlsv1.2 -sSf --max-time 300 https://sh.rustup.rs |
        sh -s -- -y --no-modify-path --profile minimal --default-toolchain none >&2 || true
    fi
  fi
  if ! command -v rustup >/dev/null 2>&1; then
    say "no cargo and no rustup, and rustup could not be installed (no apt package, no curl," \
      "or https://sh.rustup.rs unreachable): install Rust $need or later (https://rustup.rs)"
    exit 1
  fi
fi
# `cargo --version`, not `command -v cargo`: rustup's cargo is on PATH even with no toolchain
# installed, and only fails when run.
if ! cargo --version >/dev/null 2>&1; then
  if command -v rustup >/dev/null 2>&1; then
    say "no Rust toolchain; installing stable through rustup"
    if ! rustup toolchain install stable --profile minimal --component rustfmt,clippy ||
      ! rustup default stable; then
      say "rustup could not install the stable toolchain (it downloads from" \
        "static.rust-lang.org): install Rust $need or later (https://rustup.rs)"
      exit 1
    fi
  else
    say "no cargo on PATH and no rustup to install it: install Rust $need or later" \
      "(https://rustup.rs)"
    exit 1
  fi
fi
have=$(rustc --version | sed -n 's/^rustc \([0-9]*\.[0-9]*\).*/\1/p')
older() { [ "$(printf '%s\n%s\n' "$1" "$2" | sort -V | head -1)" = "$1" ] && [ "$1" != "$2" ]; }
if [ -n "$have" ] && [ -n "$need" ] && older "$have" "$need"; then
  if command -v rustup >/dev/null 2>&1; then
    say "rustc $have is older than the $need this crate needs; updating through rustup"
    rustup update stable
  else
    say "rustc $have is older than the $need this crate needs, and there is no rustup to" \
      "update it: install Rust $need or later (https://rustup.rs)"
    exit 1
  fi
fi

for tool in fmt clippy; do
  if ! cargo "$tool" --version >/dev/null 2>&1; then
    component=$([ "$tool" = fmt ] && echo rustfmt || echo clippy)
    if ! command -v rustup >/dev/null 2>&1; then
      say "cargo $tool is missing and there is no rustup to add it; install $component" \
        "with the toolchain (https://rustup.rs, or your distribution's $component package)"
      exit 1
    fi
    say "installing $component"
    rustup component add "$component"
  fi
done
cargo fmt --all -- --check
cargo clippy --release --workspace --all-targets --locked -- -D warnings
# Every doc comment's links resolve and every module doc builds: the library's docs with its
# private items, the docs a newcomer reads (links to private items are fine there).
RUSTDOCFLAGS="-D warnings -A rustdoc::private-intra-doc-links" \
  cargo doc --release --no-deps --lib --locked --document-private-items --quiet
cargo test --release --locked
