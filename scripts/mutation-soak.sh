#!/usr/bin/env bash
# Mutation soak (issue 21): every PING reply hidden among 8 mutated copies
# of itself, over UDP, TCP and a pty, for many seeds. Runs the integration
# tests in tests/it/mutants.rs (release build) once per seed with more
# exchanges, and adds up their figures.
#   scripts/mutation-soak.sh [SEEDS] [EXCHANGES]   (default 12 seeds x 4000)
#   MUTANT_TRANSPORTS="udp tcp pty" (default all three)
#   MUTANT_INTERVAL=2ms (mavping's interval)
# Each run checks, seq by seq, that the reply and every whole copy the
# peer sent were counted once (nothing lost, nothing extra). 12 seeds x
# 4000 exchanges x 3 transports x 8 copies = 1,152,000 mutants.
# Needs .venv with pymavlink (bash scripts/test.sh makes it).
set -euo pipefail
cd "$(dirname "$0")/.."
SEEDS=${1:-12}
EXCHANGES=${2:-4000}
TRANSPORTS=${MUTANT_TRANSPORTS:-udp tcp pty}
INTERVAL=${MUTANT_INTERVAL:-2ms}
export MAVPING_PYTHON=${MAVPING_PYTHON:-$PWD/.venv/bin/python}

cargo test --release --test it --no-run --quiet
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT
failed=0
start=$(date +%s)
for seed in $(seq 1 "$SEEDS"); do
  for transport in $TRANSPORTS; do
    if ! MAVPING_MUTANT_SEED=$seed MAVPING_MUTANT_EXCHANGES=$EXCHANGES \
        MAVPING_MUTANT_INTERVAL=$INTERVAL \
        cargo test --release --test it --quiet "mutants::${transport}_" \
        -- --nocapture --test-threads 1 >"$LOG.run" 2>&1; then
      failed=$((failed + 1))
      echo "FAILED: $transport seed $seed"
      grep -E "panicked|seq [0-9]+:|left|right" "$LOG.run" | head -20 || true
    fi
    grep '^mutants: ' "$LOG.run" | tee -a "$LOG"
  done
done
rm -f "$LOG.run"
wall=$(( $(date +%s) - start ))

# Totals: mutants=... intact=... missed=... extra=... redrawn=...
awk -v seeds="$SEEDS" -v wall="$wall" '
  { for (i = 3; i <= NF; i++) { split($i, kv, "="); sum[$2 "," kv[1]] += kv[2]; total[kv[1]] += kv[2] }
    runs[$2]++ }
  END {
    printf "%-5s %5s %10s %10s %8s %7s %6s %8s\n", "link", "runs", "exchanges", "mutants", "intact", "missed", "extra", "redrawn"
    for (t in runs)
      printf "%-5s %5d %10d %10d %8d %7d %6d %8d\n", t, runs[t], sum[t ",exchanges"], sum[t ",mutants"], sum[t ",intact"], sum[t ",missed"], sum[t ",extra"], sum[t ",redrawn"]
    printf "%-5s %5d %10d %10d %8d %7d %6d %8d\n", "all", NR, total["exchanges"], total["mutants"], total["intact"], total["missed"], total["extra"], total["redrawn"]
    printf "seeds 1..%d, wall time %d s\n", seeds, wall
  }' "$LOG"
if [ "$failed" -gt 0 ]; then
  echo "mutation soak: $failed run(s) FAILED"
  exit 1
fi
echo "mutation soak: every reply and every whole copy counted, nothing lost"
