#!/usr/bin/env bash
# macOS, as far as this Linux machine can go: clippy (which type-checks
# everything, tests included) for both Apple targets. Nothing is linked or
# run: that needs a Mac. The portable path compiled here is the one the
# Linux suite runs with --features portable (scripts/test.sh). ring's C goes
# through scripts/cc-apple.sh (.cargo/config.toml), which needs clang.
# Not in CI, to keep it within its time (a cold check of every dependency
# per target); scripts/test.sh runs the portable path itself there.
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang >/dev/null || {
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends clang llvm
}
for target in aarch64-apple-darwin x86_64-apple-darwin; do
  rustup target list --installed | grep -qx "$target" || rustup target add "$target"
  start=$(date +%s)
  cargo clippy --all-targets --target "$target" -- -D warnings
  echo "apple-check: $target clean in $(( $(date +%s) - start )) s"
done
