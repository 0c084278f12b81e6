#!/usr/bin/env bash
# `mavping serve` at fleet scale: 100 continuous links at 1 Hz against
# `mavping respond` (CPU and memory per link, against a 1-link server in the
# same run) and 50 concurrent /probe requests of 10 PINGs. Usage:
#   bash scripts/bench-serve.sh                  # 60 s window per case
#   WINDOW=20 LINKS=100 PROBES=50 bash scripts/bench-serve.sh
# MAVPING= picks the binary (default: a release build made here).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${MAVPING:-}" ]; then
  cargo build --release --quiet
fi
exec python3 bench/serve.py "$@"
