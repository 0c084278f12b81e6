#!/usr/bin/env bash
# Fault soak: runs mavping at 1 kHz for DURATION per case and checks every
# count against ground truth, memory and the pending table.
#   scripts/soak.sh [DURATION]        (default 10m; e.g. 180s, 3m)
#   MAVPING=target/debug/mavping scripts/soak.sh 3m   (another binary)
#   SOAK_CASES="udp pymavlink" (default: udp pymavlink sim)
# Cases:
#   udp       mavping -> `mavping respond` on loopback UDP; the responder
#             drops 1% and duplicates 1% of its replies and prints what it
#             did.
#   pymavlink mavping -> a pymavlink responder (tests/peers/responder.py)
#             that drops every 97th request and answers every 89th twice,
#             and prints what it received and did.
#   sim       the simulated link with 2 responders, 1% loss, 1% duplication,
#             2% reordering, 0.5% delay spikes past the timeout and a 5 s
#             link outage in the middle; its ground truth is logged with -v.
# Checks: counts equal ground truth exactly, in_flight == 0, every request
# counted once per responder (not charged + sent + in flight), RSS at the
# end within 1 MiB of RSS after the first second.
# (Weeks on the simulated link's virtual clock: scripts/sim-soak.sh.)
set -euo pipefail
cd "$(dirname "$0")/.."
DURATION=${1:-10m}
case "$DURATION" in
  *m) SECS=$(( ${DURATION%m} * 60 )) ;;
  *s) SECS=${DURATION%s} ;;
  *) SECS=$DURATION ;;
esac
RATE=1000
COUNT=$(( SECS * RATE ))
RSS_SLACK_KB=1024
MAVPING=${MAVPING:-target/release/mavping}
if [ ! -x "$MAVPING" ]; then
  cargo build --release --quiet
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
fail=0

rss_kb() { awk '/^VmRSS/ {print $2}' "/proc/$1/status" 2>/dev/null || echo 0; }

# Runs mavping in the background, samples its RSS once a second.
# Sets RSS_FIRST, RSS_LAST, RSS_MAX (kB).
run_sampled() {
  "$@" >"$WORK/out.json" 2>"$WORK/err.log" &
  local pid=$! t=0 rss
  RSS_FIRST=0 RSS_LAST=0 RSS_MAX=0
  while kill -0 "$pid" 2>/dev/null; do
    sleep 1
    t=$((t + 1))
    rss=$(rss_kb "$pid")
    [ "${rss:-0}" -gt 0 ] || continue
    [ "$t" -eq 1 ] && RSS_FIRST=$rss
    RSS_LAST=$rss
    [ "$rss" -gt "$RSS_MAX" ] && RSS_MAX=$rss
  done
  wait "$pid" || true
}

check() { # name expected actual
  if [ "$2" = "$3" ]; then
    printf '  ok   %-34s %s\n' "$1" "$3"
  else
    printf '  FAIL %-34s expected %s, got %s\n' "$1" "$2" "$3"
    fail=1
  fi
}

check_rss() {
  local grew=$(( RSS_LAST - RSS_FIRST ))
  printf '  RSS after 1 s %d kB, at the end %d kB (max %d kB): %+d kB\n' \
    "$RSS_FIRST" "$RSS_LAST" "$RSS_MAX" "$grew"
  if [ "${grew#-}" -gt "$RSS_SLACK_KB" ]; then
    echo "  FAIL RSS grew by more than $RSS_SLACK_KB kB"
    fail=1
  fi
}

summary() { tail -n 1 "$WORK/out.json"; }
jq_() { python3 -c "import json,sys; s=json.loads(sys.stdin.read()); print($1)"; }
free_port() {
  python3 -c 'import socket; s=socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# What every case checks of responder $2 (a Python expression) in summary $1.
check_common() {
  local s=$1 r=$2
  check "in flight at the end" 0 "$(jq_ 's["in_flight"]' <<<"$s")"
  check "sent = received + lost" "$(jq_ "$r['received']+$r['lost']" <<<"$s")" "$(jq_ "$r['sent']" <<<"$s")"
  check "not charged + sent + in flight" "$(jq_ 's["requests"]' <<<"$s")" \
    "$(jq_ "$r['not_charged']+$r['sent']+$r['in_flight']" <<<"$s")"
  check "stale" 0 "$(jq_ "$r['stale']" <<<"$s")"
  echo "  mavping: $(jq_ "{k: $r[k] for k in ('not_charged','sent','received','lost','late','duplicate','out_of_order')}" <<<"$s")"
  echo "  rtt p50/p99/max us: $(jq_ "($r['rtt_us']['p50'], $r['rtt_us']['p99'], $r['rtt_us']['max'])" <<<"$s"); send lateness p50/p99/max us: $(jq_ "(s['schedule']['lateness_p50_us'], s['schedule']['lateness_p99_us'], s['schedule']['lateness_max_us'])" <<<"$s")"
}

soak_udp() {
  local port
  port=$(free_port)
  "$MAVPING" respond --drop 1 --dup 1 --seed 5 "udpin:127.0.0.1:$port" >"$WORK/respond.log" 2>&1 &
  local rpid=$!
  sleep 0.5
  echo "== udp: $COUNT PINGs at $RATE/s to mavping respond (1% dropped, 1% duplicated)"
  run_sampled "$MAVPING" --json -q --rate "$RATE" -c "$COUNT" -W 1s "udpout:127.0.0.1:$port"
  kill -TERM "$rpid"
  wait "$rpid" || true
  local line
  line=$(grep -E 'replies sent' "$WORK/respond.log" | tail -n 1)
  echo "  responder: $line"
  local requests replies dropped duplicated
  requests=$(sed -E 's/.*: ([0-9]+) requests.*/\1/' <<<"$line")
  replies=$(sed -E 's/.*, ([0-9]+) replies sent.*/\1/' <<<"$line")
  dropped=$(sed -E 's/.* ([0-9]+) dropped.*/\1/' <<<"$line")
  duplicated=$(sed -E 's/.* ([0-9]+) duplicated.*/\1/' <<<"$line")
  local s
  s=$(summary)
  local r='s["responders"][0]'
  check "requests sent = heard by responder" "$requests" "$(jq_ 's["requests"]' <<<"$s")"
  check "received + late + dup = replies" "$replies" "$(jq_ "$r['received']+$r['late']+$r['duplicate']" <<<"$s")"
  check "lost + not charged = dropped" "$dropped" "$(jq_ "$r['lost']+$r['not_charged']" <<<"$s")"
  check "duplicate = duplicated" "$duplicated" "$(jq_ "$r['duplicate']" <<<"$s")"
  check_common "$s" "$r"
  check_rss
}

soak_pymavlink() {
  local port
  port=$(free_port)
  local python=python3
  [ -x .venv/bin/python3 ] && python=.venv/bin/python3
  "$python" -u tests/peers/responder.py "udpin:127.0.0.1:$port" --drop-every 97 --dup-every 89 \
    --heartbeat-hz 1 >"$WORK/pymavlink.log" 2>&1 &
  local rpid=$!
  sleep 1
  echo "== pymavlink: $COUNT PINGs at $RATE/s to a pymavlink responder (every 97th dropped, every 89th answered twice)"
  run_sampled "$MAVPING" --json -q --rate "$RATE" -c "$COUNT" -W 1s "udpout:127.0.0.1:$port"
  kill -TERM "$rpid"
  wait "$rpid" || true
  local truth
  truth=$(grep -E '^\{' "$WORK/pymavlink.log" | tail -n 1)
  echo "  responder: $truth"
  local s
  s=$(summary)
  local r='s["responders"][0]'
  local heard replies dropped duplicated
  heard=$(jq_ 's["ping_requests"]' <<<"$truth")
  replies=$(jq_ 's["replies"]' <<<"$truth")
  dropped=$(jq_ 's["dropped"]' <<<"$truth")
  duplicated=$(jq_ 's["duplicated"]' <<<"$truth")
  # Requests the responder never read (its socket buffer overflowed while
  # Python was busy) are lost too; its own count says how many.
  local unheard=$(( $(jq_ 's["requests"]' <<<"$s") - heard ))
  echo "  requests the responder did not receive: $unheard"
  check "received + late = replies" "$replies" "$(jq_ "$r['received']+$r['late']" <<<"$s")"
  check "lost + not charged = dropped + unheard" "$(( dropped + unheard ))" "$(jq_ "$r['lost']+$r['not_charged']" <<<"$s")"
  check "duplicate = duplicated" "$duplicated" "$(jq_ "$r['duplicate']" <<<"$s")"
  check_common "$s" "$r"
  check_rss
}

soak_sim() {
  local half=$(( SECS / 2 ))
  local link="sim:?responders=2&delay=2ms&jitter=1ms&loss=1%&dup=1%&reorder=2%&hold=20ms&spike=0.5%&spike_delay=400ms&outage=${half}s+5s&seed=11"
  echo "== sim: $COUNT PINGs at $RATE/s, $link"
  run_sampled env MAVPING_LOG=mavping=info "$MAVPING" -v --json -q --rate "$RATE" -c "$COUNT" -W 200ms "$link"
  local s
  s=$(summary)
  local i=0
  while read -r truth; do
    # sim truth 1/1: answered=.. dropped=.. dropped_before_first=.. delivered=.. duplicated=..
    #   duplicates_arrived=.. outage=.. spiked=.. spiked_arrived=..
    declare -A t=()
    for kv in $(grep -oE '[a-z_]+=[0-9]+' <<<"${truth%% link=*}"); do t[${kv%%=*}]=${kv#*=}; done
    local r="s['responders'][$i]"
    echo "  responder $i truth: $(grep -oE '[0-9]+/[0-9]+: .*' <<<"${truth%% link=*}")"
    check "[$i] not charged = dropped before first" "${t[dropped_before_first]}" "$(jq_ "$r['not_charged']" <<<"$s")"
    check "[$i] sent = answered - before first" $(( t[answered] - t[dropped_before_first] )) "$(jq_ "$r['sent']" <<<"$s")"
    check "[$i] received = delivered" "${t[delivered]}" "$(jq_ "$r['received']" <<<"$s")"
    check "[$i] lost = dropped (in window) + spiked" $(( t[dropped] - t[dropped_before_first] + t[spiked] )) "$(jq_ "$r['lost']" <<<"$s")"
    check "[$i] late = spiked replies that arrived" "${t[spiked_arrived]}" "$(jq_ "$r['late']" <<<"$s")"
    check "[$i] duplicate = copies that arrived" "${t[duplicates_arrived]}" "$(jq_ "$r['duplicate']" <<<"$s")"
    echo "  outage lost ${t[outage]} exchanges"
    check_common "$s" "$r"
    i=$((i + 1))
    unset t
  done < <(grep -E 'sim truth' "$WORK/err.log" | sed 's/\x1b\[[0-9;]*m//g')
  check "responders with truth" 2 "$i"
  check_rss
}

for c in ${SOAK_CASES:-udp pymavlink sim}; do
  "soak_$c"
done
if [ "$fail" -ne 0 ]; then
  echo "soak: FAILED"
  exit 1
fi
echo "soak: all counts exact, memory flat"
