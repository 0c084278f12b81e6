#!/usr/bin/env bash
# mavping's benchmark: builds in release mode, starts the responders itself,
# runs irtt, a pymavlink pinger (the baseline) and mavping in the same run,
# and prints a table of figures and ratios. Usage:
#   bash scripts/bench.sh          # full run (about 9 minutes)
#   bash scripts/bench.sh --quick  # shorter trials (about 4 minutes)
#   bash scripts/bench.sh --binary /tmp/before/target/release/mavping
#                                  # the same bench against another build
#                                  # (for a before/after table)
#   bash scripts/bench.sh --portable # only the portable path's rows beside
#                                  # the Linux path's (about 1 minute)
#   bash scripts/bench.sh --passive  # only the passive rows (about 2 minutes):
#                                  # --passive at 100,000 frames/s beside a
#                                  # plain reader and pymavlink's mavutil
#   bash scripts/bench.sh --passive --age-against OLD_BINARY  # --passive's CPU
#                                  # per frame with age tracking beside a
#                                  # build without it, same run (issue 40)
#   bash scripts/bench.sh --passive --pair  # one vehicle on two links (issue
#                                  # 41, about 3 minutes): --passive's CPU per
#                                  # frame on one link at 50,000 frames/s
#                                  # beside two links fed the same frames,
#                                  # 50,000/s each, same run, with the plain
#                                  # reader and pymavlink on one and two; the
#                                  # counts held to the sender's less the
#                                  # kernel's drops, the pair report to the
#                                  # sender's
#   bash scripts/bench.sh --passive --pair --pair-against OLD_BINARY  # and
#                                  # a build without the pair tracker on the
#                                  # same two links: the tracker's own cost
#   bash scripts/bench.sh --transfers  # a 1,000-parameter download against
#                                  # mavping respond on loopback (issue 42,
#                                  # about 1 minute): --probe params beside
#                                  # MAVProxy's param fetch of the same set,
#                                  # same responder, time and CPU each
#   bash scripts/bench.sh --ws      # PINGs over ws:// beside UDP and TCP to
#                                  # one mavping respond (issue 43, about 1
#                                  # minute): RTT p50/p99 and CPU per PING
# Not run by CI (it needs a quiet machine and minutes).
# Micro-benchmarks of the parser, matcher and statistics: cargo bench --bench core
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
# The sender and the plain reader of the passive rows (examples/stream_floor.rs).
cargo build --release --quiet --example stream_floor
if [ ! -x /usr/bin/time ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  apt-get install -y -qq time >/dev/null  # GNU time: per-process peak RSS and CPU
fi
if [ "${1:-}" = --ws ]; then
  shift
  exec .venv/bin/python bench/ws.py target/release/mavping "$@"
fi
if [ "${1:-}" = --transfers ]; then
  shift
  exec .venv/bin/python bench/transfers.py target/release/mavping .venv/bin/mavproxy.py "$@"
fi
# The passive rows need neither the portable build, the wake floor nor irtt.
if [ "${1:-}" != --passive ]; then
  # The portable path (Windows', macOS') on Linux, in its own target
  # directory so the release binary above stays the Linux path.
  cargo build --release --quiet --features portable --target-dir target/portable
  # The baseline of the CPU-per-PING rows: a loop that only sleeps, reads and
  # sends once per PING (examples/wake_floor.rs).
  cargo build --release --quiet --example wake_floor
  if ! command -v irtt >/dev/null; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
      apt-get install -y -qq irtt >/dev/null || echo "bench: could not install irtt; its rows are skipped"
    else
      echo "bench: irtt is not installed (Debian: apt-get install irtt); its rows are skipped"
    fi
  fi
fi
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import pymavlink" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check "pymavlink==2.4.50" pyserial==3.5
fi
if [ "${1:-}" = --passive ]; then
  shift
  exec .venv/bin/python bench/passive.py "$@"
fi
exec .venv/bin/python bench/run.py "$@"
