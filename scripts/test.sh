#!/usr/bin/env bash
# Runs every test on a fresh Debian machine: installs what the tests need
# (Graphviz for the DOT export check), then the workspace tests and a quick
# pass of the criterion benches so they keep building and running.
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
command -v dot >/dev/null 2>&1 || missing+=(graphviz)
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" = 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

cargo fmt --all -- --check
cargo test --workspace --release --locked
# Benches report, they do not assert; --quick keeps this to seconds.
cargo bench --locked --bench graph_compile -- --quick
