#!/usr/bin/env bash
# Weeks of monitoring in minutes: mavping on the simulated link's virtual
# clock, every count checked against the link's ground truth, the PING seq
# wrapping past 2^32 inside the run, RSS at the end equal to RSS after the
# first simulated hour (within 1 MiB).
#   scripts/sim-soak.sh [CASE...]     (default: week day)
#   MAVPING=target/debug/mavping scripts/sim-soak.sh hours   (another binary)
# Cases (the faults: loss, duplication, reordering, delay spikes past the
# timeout, an outage every few hours; scripts/sim_soak.py lists them):
#   week   a simulated week at 10 Hz, 2 responders (6,048,000 PINGs)
#   day    a simulated day at 1 kHz (86,400,000 PINGs)
#   hours  three simulated hours at 1 kHz (10,800,000 PINGs)
set -euo pipefail
cd "$(dirname "$0")/.."
MAVPING=${MAVPING:-target/release/mavping}
if [ ! -x "$MAVPING" ]; then
  cargo build --release --quiet
fi
exec python3 scripts/sim_soak.py "$MAVPING" "$@"
