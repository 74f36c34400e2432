#!/usr/bin/env bash
# CI smoke test of the fuzz crate (fuzz/, see fuzz/README.md): builds every
# target once with cargo-fuzz's defaults (release, debug assertions and
# overflow checks, AddressSanitizer), then runs each for FUZZ_SMOKE_SECONDS
# (10) over its committed corpus under the campaigns' limits. Any crash,
# panic, failed assertion, out-of-memory or timeout fails the script (after
# every target has run); libFuzzer's artefact is left in fuzz/artifacts/.
# New inputs go to a scratch directory: the committed corpora stay as they are.
#
# Needs a nightly toolchain and cargo-fuzz, and installs them when missing
# (rustup, cargo install); fails, never skips, when that does not work.
# FUZZ_TARGET_DIR: the build directory (default fuzz/target).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds="${FUZZ_SMOKE_SECONDS:-10}"
target_dir="${FUZZ_TARGET_DIR:-fuzz/target}"

# Installs what is missing, as scripts/test.sh does for packages; fails
# (never skips) when that does not work.
if ! cargo +nightly --version >/dev/null 2>&1; then
  echo "fuzz_smoke.sh: installing the nightly toolchain"
  rustup toolchain install nightly --profile minimal ||
    { echo "fuzz_smoke.sh: no nightly toolchain; install it with: rustup toolchain install nightly" >&2; exit 1; }
fi
if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
  echo "fuzz_smoke.sh: installing cargo-fuzz"
  cargo install cargo-fuzz --locked ||
    { echo "fuzz_smoke.sh: no cargo-fuzz; install it with: cargo install cargo-fuzz" >&2; exit 1; }
fi

# The longest input each target is fuzzed with (as in the campaigns).
max_len() {
  case "$1" in
    compile) echo 8192 ;;
    envmap_exr | envmap_hdr | scene_ron) echo 16384 ;;
    param) echo 1024 ;;
    *) echo 4096 ;;
  esac
}

start=$(date +%s)
cargo +nightly fuzz build --target-dir "$target_dir"
built=$(date +%s)
host=$(rustc +nightly -vV | sed -n 's/^host: //p')
bin_dir="$target_dir/$host/release"

scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
failed=()
for t in $(cargo +nightly fuzz list); do
  corpus="fuzz/corpus/$t"
  if [ ! -d "$corpus" ]; then
    echo "fuzz_smoke.sh: $t has no committed corpus ($corpus)" >&2
    failed+=("$t")
    continue
  fi
  mkdir -p "$scratch/$t" "fuzz/artifacts/$t"
  echo "== $t ($seconds s over $(ls "$corpus" | wc -l) inputs)"
  if ! "$bin_dir/$t" "$scratch/$t" "$corpus" \
    -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=1024 \
    -timeout=10 -max_len="$(max_len "$t")" -print_final_stats=1 \
    -artifact_prefix="fuzz/artifacts/$t/" >"$scratch/$t.log" 2>&1; then
    tail -n 40 "$scratch/$t.log"
    failed+=("$t")
  fi
  grep -E '^(#[0-9]+[[:space:]]+DONE|stat::number_of_executed_units)' "$scratch/$t.log" || true
done
end=$(date +%s)
echo "fuzz smoke: build $((built - start)) s, runs $((end - built)) s"
if ((${#failed[@]})); then
  echo "fuzz smoke FAILED: ${failed[*]} (artefacts in fuzz/artifacts/)" >&2
  exit 1
fi
echo "fuzz smoke: every target ran ${seconds} s without a crash"
