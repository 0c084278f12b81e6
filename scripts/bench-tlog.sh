#!/usr/bin/env bash
# Telemetry-log analysis: mavping `tlog:` against pymavlink's mavloss.py on
# the same files, in the same run, and mavping's peak RSS on a small and a
# ten times larger log. Builds in release mode and generates the logs with
# scripts/tlog_gen.py (pymavlink). Usage:
#   bash scripts/bench-tlog.sh           # 2 h at 50 frames/s, 20 MB and 200 MB (about 6 minutes)
#   bash scripts/bench-tlog.sh --quick   # 2 h at 50 frames/s and 20 MB only
#   bash scripts/bench-tlog.sh --binary PATH   # another mavping build
# Times are wall clock and CPU (user + system) of each whole process; the
# ratio is mavloss.py's CPU time over mavping's.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
bin=target/release/mavping
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --binary) bin="$2"; shift ;;
    *) echo "bench-tlog: unknown argument $1" >&2; exit 2 ;;
  esac
  shift
done
[ "$bin" = target/release/mavping ] && cargo build --release --quiet
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import pymavlink" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check "pymavlink==2.4.50" pyserial==3.5
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
py=.venv/bin/python
gen() { "$py" scripts/tlog_gen.py "$dir/$1" --seconds "$2" --rate "$3" --stamps "${4:-us}"; }
gen flight-2h.tlog 7200 50            # a two-hour flight at 50 frames/s, ~17 MB
gen log-20mb.tlog 1760 250            # ~20 MB
[ "$quick" = 1 ] || gen log-200mb.tlog 17600 250   # ~200 MB
[ "$quick" = 1 ] || gen log-200mb-ms.tlog 17600 250 ms
# "wall s, cpu s, peak RSS KB" of a command, its output discarded.
measure() {
  /usr/bin/time -f "%e %U %S %M" -o "$dir/time" "$@" >/dev/null 2>&1
  awk '{printf "%s %.2f %s\n", $1, $2 + $3, $4}' "$dir/time"
}
frames() { "$bin" --json -q "tlog:$1" | "$py" -c 'import json,sys; print(json.loads(sys.stdin.read())["log"]["records"]["records"])'; }
printf "| log | size | frames | mavping wall / CPU s | mavping frames/s (CPU) | mavping MB/s (CPU) | peak RSS | mavloss.py wall / CPU s | CPU ratio |\n"
printf "|---|---|---|---|---|---|---|---|---|\n"
# The ms log (QGroundControl's stamps: no link numbers to split by) is read
# by mavping only; mavloss.py reads it as it reads the others.
for log in flight-2h.tlog log-20mb.tlog log-200mb.tlog log-200mb-ms.tlog; do
  [ -f "$dir/$log" ] || continue
  size=$(stat -c %s "$dir/$log")
  n=$(frames "$dir/$log")
  read -r mw mc mr < <(measure "$bin" -q "tlog:$dir/$log")
  lw=-; lc=-
  [ "$log" = log-200mb-ms.tlog ] || read -r lw lc _ < <(measure "$py" .venv/bin/mavloss.py "$dir/$log")
  awk -v name="$log" -v size="$size" -v n="$n" -v mw="$mw" -v mc="$mc" -v mr="$mr" -v lw="$lw" -v lc="$lc" 'BEGIN {
    cpu = (mc > 0) ? mc : 0.01
    ratio = (lc == "-") ? "-" : sprintf("%.0fx", lc / cpu)
    printf "| %s | %.1f MB | %d | %s / %s | %.2fM | %.0f | %.1f MB | %s / %s | %s |\n",
      name, size / 1e6, n, mw, mc, n / cpu / 1e6, size / 1e6 / cpu, mr / 1024, lw, lc, ratio
  }'
done
