#!/usr/bin/env bash
# Runs the same invocations under two builds of mavping and diffs everything
# they write (stdout, stderr, exit code, and the files --plot, --samples,
# --hgrm and --prometheus-textfile make): the check a restructuring must
# pass, byte for byte. Every run is on the simulated link's virtual clock or
# a telemetry log, so nothing in it depends on the time it runs.
#
#   bash scripts/same-output.sh BEFORE_BINARY AFTER_BINARY
#
# Exits 0 when every output is the same; else prints the first lines of
# each difference and exits 1.
set -u
before=$(realpath "${1:?usage: same-output.sh BEFORE_BINARY AFTER_BINARY}")
after=$(realpath "${2:?usage: same-output.sh BEFORE_BINARY AFTER_BINARY}")
logs=$(cd "$(dirname "$0")/../../shared/tlogs" 2>/dev/null && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

V='clock=virtual'
invocations=(
  # README's first example, and the echo run in each format
  "-c 10 -i 0.2 sim:?responders=2&loss=10%&jitter=5ms&seed=3&$V"
  "-c 20 -i 50ms -q sim:?responders=2&loss=10%&dup=5%&reorder=5%&seed=4&$V"
  "-c 20 -i 50ms --json sim:?responders=2&loss=10%&dup=5%&reorder=5%&seed=4&$V"
  "-c 20 -i 50ms -D -v sim:?loss=20%&hold=300ms&seed=5&$V"
  "-c 30 -i 20ms --every-reply -W 40ms sim:?jitter=30ms&dup=10%&seed=6&$V"
  "-c 40 -i 20ms -Q 200ms sim:?seed=7&$V"
  "-c 40 -i 20ms -Q 200ms --json sim:?seed=7&$V"
  "-c 50 -i 10ms --max-loss 5% --max-rtt p99=20ms --expect 1/1 --min-responders 2 sim:?loss=10%&seed=8&$V"
  "-c 50 -i 10ms --json --max-loss 5% --max-rtt p99=20ms --expect 1/1 sim:?loss=10%&seed=8&$V"
  "-c 20 -i 50ms --live sim:?responders=2&seed=3&$V"
  "-c 20 -i 50ms --format json -q sim:?outage=300ms+200ms&spike=10%&spike_delay=1s&seed=4&$V"
  # timesync, auto against a responder that answers no PING
  "-c 20 -i 100ms --probe timesync sim:?offset=2s&drift=-30&jitter=4ms&seed=9&$V"
  "-c 20 -i 100ms --probe timesync --json sim:?offset=2s&drift=-30&jitter=4ms&seed=9&$V"
  "-c 20 -i 100ms sim:?ping=off&seed=9&$V"
  # command
  "-c 10 -i 100ms --probe command sim:?loss=30%&seed=10&$V"
  "-c 10 -i 100ms --probe command --json sim:?loss=30%&seed=10&$V"
  "-c 5 -i 100ms --probe command --command 520 sim:?loss=100%&$V"
  "-c 5 --probe command --retries 1 --json sim:?ping=off&$V"
  # several links
  "-c 10 -i 50ms sim:?$V sim:?delay=50ms&$V"
  "-c 10 -i 50ms --json sim:?$V sim:?delay=50ms&loss=20%&seed=3&$V"
  # sweep, load, radio
  "--sweep --sweep-max 200 --step 500ms sim:?baud=57600&radio=on&seed=11&$V"
  "--sweep --sweep-max 200 --step 500ms --json sim:?baud=57600&radio=on&seed=11&$V"
  "-c 30 -i 100ms sim:?baud=57600&radio=on&seed=12&$V"
  "-c 30 -i 100ms --json sim:?baud=57600&radio=on&seed=12&$V"
  "-i 50ms --load ATTITUDE@50 --step 500ms sim:?baud=57600&radio=on&seed=13&$V"
  "-i 50ms --load ATTITUDE@50 --step 500ms --json sim:?baud=57600&radio=on&seed=13&$V"
  # passive
  "--passive -w 3s sim:?responders=2&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5&loss=5%&seed=14&$V"
  "--passive -w 3s --json sim:?responders=2&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5&loss=5%&seed=14&$V"
  "--passive -w 3s -Q 1s --json sim:?responders=2&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5&loss=5%&seed=14&$V"
  "-c 30 -i 50ms sim:?stream=ATTITUDE@50&loss_down=5%&loss_up=10%&seed=15&$V"
  # bad input
  "sim:?loss=abc"
  "-c 0 sim:"
  "--max-loss 200% sim:"
  "udp:999.1.1.1:14550"
  "tlog:/nonexistent.tlog"
)
for log in "$logs"/*.tlog; do
  invocations+=("$log" "-q $log" "--json $log" "-v $log")
done

n=0
differ=0
for args in "${invocations[@]}"; do
  n=$((n + 1))
  for side in before after; do
    bin=$before
    [ "$side" = after ] && bin=$after
    d="$work/$side/$n"
    mkdir -p "$d/files"
    # Bare, then with every file output (a run that refuses one says so
    # the same way under both builds).
    # shellcheck disable=SC2086
    (cd "$d" && timeout 120 "$bin" $args >stdout 2>stderr </dev/null; echo $? >code)
    # shellcheck disable=SC2086
    (cd "$d/files" && timeout 120 "$bin" $args --plot plot.svg --samples samples.csv \
      --hgrm rtt.hgrm --prometheus-textfile metrics.prom >stdout 2>stderr </dev/null
    echo $? >code)
  done
  # The two wall-clock figures: when the run ended (the textfile), and
  # the time of each -v log line.
  sed -i '/^mavping_textfile_run_end_timestamp_seconds /d' "$work"/*/"$n"/files/metrics.prom 2>/dev/null
  sed -i -E 's/^[0-9]{4}-[0-9-]+T[0-9:.]+Z +//' "$work"/*/"$n"/stderr "$work"/*/"$n"/files/stderr
  if ! diff -r "$work/before/$n" "$work/after/$n" >"$work/diff" 2>&1; then
    differ=$((differ + 1))
    echo "DIFFERS: mavping $args"
    head -20 "$work/diff"
  fi
done
echo "$n invocations, $differ differ"
[ "$differ" -eq 0 ]
