#!/usr/bin/env bash
# Telemetry-log analysis: mavping `tlog:` against pymavlink's mavloss.py on
# the same files, in the same run, and mavping's peak RSS on a small and a
# ten times larger log. Builds in release mode and generates the logs with
# scripts/tlog_gen.py (pymavlink). Usage:
#   bash scripts/bench-tlog.sh           # 2 h at 50 frames/s, 20 MB and 200 MB (about 6 minutes)
#   bash scripts/bench-tlog.sh --quick   # 2 h at 50 frames/s and 20 MB only
#   bash scripts/bench-tlog.sh --binary PATH   # another mavping build
#   bash scripts/bench-tlog.sh --quick --baseline PATH   # and a table of
#       this build against an earlier one (PATH) on the same logs, the two
#       read in turn five times each, medians of their CPU
# Times are wall clock and CPU (user + system) of each whole process; the
# ratio is mavloss.py's CPU time over mavping's.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
bin=target/release/mavping
baseline=
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --binary) bin="$2"; shift ;;
    --baseline) baseline="$2"; shift ;;
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

[ -n "$baseline" ] || exit 0
# This build against the baseline, read in turn so that a busy moment falls
# on both: the generated logs and the real ones in ../shared/tlogs.
median() { sort -n | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
# CPU of one read to the microsecond (getrusage of the child; time(1)
# rounds to 10 ms, as long as a small log's whole read).
cpu_of() {
  "$py" -c 'import resource, subprocess, sys
subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
r = resource.getrusage(resource.RUSAGE_CHILDREN)
print(f"{r.ru_utime + r.ru_stime:.4f}")' "$1" -q "tlog:$2"
}
printf "\n| log | frames | baseline CPU s (median of 5) | this build CPU s (median of 5) | change |\n|---|---|---|---|---|\n"
for log in "$dir"/flight-2h.tlog "$dir"/log-20mb.tlog ../shared/tlogs/*.tlog; do
  [ -f "$log" ] || continue
  n=$(frames "$log")
  : >"$dir/base"; : >"$dir/this"
  for _ in 1 2 3 4 5; do
    cpu_of "$baseline" "$log" >>"$dir/base"
    cpu_of "$bin" "$log" >>"$dir/this"
  done
  b=$(median <"$dir/base"); t=$(median <"$dir/this")
  awk -v name="$(basename "$log")" -v n="$n" -v b="$b" -v t="$t" 'BEGIN {
    printf "| %s | %d | %.4f | %.4f | %+.1f%% |\n", name, n, b, t, (b > 0) ? 100 * (t - b) / b : 0
  }'
done
