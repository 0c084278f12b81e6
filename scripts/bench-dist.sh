#!/usr/bin/env bash
# What the shipped binary's size tuning costs: the static x86_64 build in
# the `dist` profile (opt-level "s", its cold dependencies "z", as
# scripts/dist.sh builds it) beside
# the same build at opt-level 3, run in turn by bench/dist.py (1 kHz,
# 150k PINGs/s with exact counts, reading a 20 MB tlog). About 4 minutes
# of runs, plus the two builds (about 4 and 6 minutes cold). Not run by CI.
#   bash scripts/bench-dist.sh [--rounds N]
set -euo pipefail
cd "$(dirname "$0")/.."
t=x86_64-unknown-linux-musl
rustup target list --installed | grep -qx "$t" || rustup target add "$t"
cargo build --release --quiet  # the responder, the same for both
cargo build --locked --quiet --profile dist --target "$t" --target-dir "target/dist-build/$t"
# Everything at opt-level 3: the profile and each per-package override
# in Cargo.toml ("*" and the hot crates), or the comparison would keep them.
opt3=(--config 'profile.dist.opt-level=3' --config 'profile.dist.package."*".opt-level=3')
for p in $(sed -nE 's/^\[profile\.dist\.package\.([A-Za-z0-9_-]+)\]$/\1/p' Cargo.toml); do
  opt3+=(--config "profile.dist.package.$p.opt-level=3")
done
cargo "${opt3[@]}" build --locked --quiet --profile dist --target "$t" --target-dir target/dist-opt3
[ -x /usr/bin/time ] || apt-get install -y -qq time >/dev/null
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import pymavlink" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check "pymavlink==2.4.50" pyserial==3.5
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
.venv/bin/python scripts/tlog_gen.py "$dir/log-20mb.tlog" --seconds 1760 --rate 250
cd bench
../.venv/bin/python dist.py "../target/dist-build/$t/$t/dist/mavping" "../target/dist-opt3/$t/dist/mavping" \
  "$dir/log-20mb.tlog" "$@"
