#!/usr/bin/env bash
# Runs mavping binaries built for other CPUs, not only builds them: under
# qemu-user (qemu-aarch64, qemu-arm) each binary
#   1. prints its version;
#   2. runs the simulated link with a seeded loss on the virtual clock and
#      must count exactly what the native binary counts on the same seed
#      (same sent/received/lost/duplicate per responder, same exit code 0),
#      then ends with exit 1 when nothing answers and exit 2 on bad input;
#   3. pings the native `mavping respond` over UDP (respond drops and
#      duplicates seeded shares of its replies): the pinger's sent, received,
#      lost and duplicate must equal what respond says it received, dropped
#      and duplicated;
#   4. is the responder for the native pinger, the same way round reversed.
# Host names are resolved by the foreign binary (udpout:localhost:PORT), as a
# user's link strings are.
#
# Usage: scripts/cross-test.sh [--profile P] [--target-dir D] [--native PATH] TARGET[=BINARY]...
#   --profile P     the cargo profile's directory the binaries were built in
#                   (dist; debug for the dev profile)
#   --target-dir D  cargo's target directory (target)
#   --native PATH   the host binary playing the other end (target/debug/mavping)
# A target's binary is BINARY when given, else D/TARGET/P/mavping; build it
# first (scripts/dist.sh and scripts/test.sh do). A missing qemu is a
# failure, not a skip.
set -euo pipefail
cd "$(dirname "$0")/.."

profile=dist
target_dir=target
native=target/debug/mavping
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --profile) profile=$2; shift 2 ;;
    --target-dir) target_dir=$2; shift 2 ;;
    --native) native=$2; shift 2 ;;
    -*) echo "cross-test: unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || { echo "usage: scripts/cross-test.sh [--profile P] [--target-dir D] [--native PATH] TARGET[=BINARY]..." >&2; exit 2; }
[ -x "$native" ] || { echo "cross-test: FAIL: no native binary at $native (cargo build first)" >&2; exit 1; }

work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT

fail() {
  echo "cross-test: FAIL: $*" >&2
  exit 1
}

# The emulator for a target's CPU, empty for the host's own.
runner_for() {
  local exe
  case "$1" in
    x86_64-*) return 0 ;;
    aarch64-*) exe=qemu-aarch64 ;;
    armv7-* | arm-* | thumbv7*) exe=qemu-arm ;;
    *) fail "no emulator known for $1" ;;
  esac
  command -v "$exe" >/dev/null ||
    fail "$exe is missing: install Debian's qemu-user (apt-get install qemu-user) to run $1 binaries"
  echo "$exe"
}

free_udp_port() {
  python3 -c 'import socket; s=socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# "sent received lost duplicate exit_code" of responder SYS/COMP in a JSON
# summary (the last line of `--json -q`); with a third argument, then its
# not_charged and the link's requests.
json_counts() {
  python3 - "$@" <<'EOF'
import json, sys
lines = [l for l in open(sys.argv[1]) if l.strip()]
s = json.loads(lines[-1])
assert s["type"] == "summary", s["type"]
sys_, comp = map(int, sys.argv[2].split("/"))
for r in s["responders"]:
    if (r["responder"]["sysid"], r["responder"]["compid"]) == (sys_, comp):
        extra = f' {r["not_charged"]} {s["requests"]}' if len(sys.argv) > 3 else ""
        print(r["sent"], r["received"], r["lost"], r["duplicate"], s["exit_code"], end=extra + "\n")
        break
else:
    print("absent", s["exit_code"])
EOF
}

# "requests ping timesync replies dropped duplicated" from respond's last line.
respond_counts() {
  sed -nE 's/^respond [0-9]+\/[0-9]+: ([0-9]+) requests \(([0-9]+) ping, ([0-9]+) timesync, [0-9]+ command, [0-9]+ command retransmissions\), ([0-9]+) replies sent, ([0-9]+) dropped, ([0-9]+) duplicated.*/\1 \2 \3 \4 \5 \6/p' "$1"
}

# Starts `respond` (runner, binary, args...) in the background, its output
# in $work/respond.out, and returns once its link is open.
start_respond() {
  : >"$work/respond.out"
  "$@" >"$work/respond.out" 2>"$work/respond.err" &
  respond_pid=$!
  pids+=("$respond_pid")
  for _ in $(seq 100); do
    grep -q '^mavping respond:' "$work/respond.out" && return 0
    kill -0 "$respond_pid" 2>/dev/null || fail "respond ended before its link was open: $(cat "$work/respond.err")"
    sleep 0.2
  done
  fail "respond did not open its link in 20 s"
}

# Stops the responder as a user does (SIGTERM) and checks it ended cleanly.
stop_respond() {
  kill -TERM "$respond_pid"
  local code=0
  wait "$respond_pid" || code=$?
  [ "$code" = 0 ] || fail "respond exited $code on SIGTERM: $(cat "$work/respond.err")"
}

# The pinger's counts against respond's ground truth: every request heard,
# every drop a loss, every duplicate seen.
check_udp_counts() {
  local label=$1 requests=$2 ping_counts respond
  ping_counts=$(json_counts "$work/ping.json" 1/1 all)
  respond=$(respond_counts "$work/respond.out")
  [ -n "$respond" ] || fail "$label: no counts from respond: $(cat "$work/respond.out")"
  # A request sent before the responder was first heard is not charged to
  # it (docs/measuring.md): when respond dropped that one, it is neither
  # sent nor lost for 1/1, and counted in not_charged.
  read -r sent received lost duplicate code not_charged link_requests <<<"$ping_counts"
  read -r r_requests r_ping r_timesync r_replies r_dropped r_duplicated <<<"$respond"
  [ "$code" = 0 ] || fail "$label: pinger exit code $code, expected 0"
  [ "$link_requests" = "$requests" ] || fail "$label: pinger sent $link_requests requests, expected $requests"
  [ $((sent + not_charged)) = "$requests" ] ||
    fail "$label: pinger charged $sent and did not charge $not_charged of $requests"
  [ "$r_ping" = "$requests" ] && [ "$r_timesync" = 0 ] ||
    fail "$label: respond heard $r_ping PING and $r_timesync TIMESYNC, expected $requests and 0"
  [ $((lost + not_charged)) = "$r_dropped" ] ||
    fail "$label: pinger lost $lost (and $not_charged not charged), respond dropped $r_dropped"
  [ "$received" = $((requests - r_dropped)) ] ||
    fail "$label: pinger received $received, respond answered $((requests - r_dropped))"
  [ "$duplicate" = "$r_duplicated" ] || fail "$label: pinger saw $duplicate duplicates, respond sent $r_duplicated"
  [ "$r_dropped" -gt 0 ] && [ "$r_duplicated" -gt 0 ] ||
    fail "$label: the seeded faults did not happen (dropped $r_dropped, duplicated $r_duplicated)"
  echo "  $label: pinger $link_requests requests, $sent sent to 1/1 ($not_charged before it was heard), $received received, $lost lost, $duplicate duplicate (exit $code);" \
    "respond $r_requests requests ($r_ping ping), $r_replies replies sent, $r_dropped dropped, $r_duplicated duplicated (exit 0)"
}

version=$(sed -nE 's/^version = "(.*)"/\1/p' Cargo.toml | head -1)
requests=40
# 2 responders, seeded loss and duplicates, on the virtual clock: the same
# counts on every CPU, or the foreign build computes something else.
sim='sim:?responders=2&loss=15%&dup=5%&seed=11&clock=virtual'
"$native" --json -q -c 50 -i 0.02 "$sim" >"$work/native-sim.json" || true
native_sim="$(json_counts "$work/native-sim.json" 1/1) / $(json_counts "$work/native-sim.json" 2/1)"

for arg in "${targets[@]}"; do
  target=${arg%%=*}
  bin=$target_dir/$target/$profile/mavping
  [ "$arg" = "$target" ] || bin=${arg#*=}
  [ -x "$bin" ] || fail "no binary at $bin (build it: cargo build --profile $profile --target $target)"
  runner=$(runner_for "$target")
  run=($runner "$bin")
  echo "cross-test $target (${runner:-native}), $bin:"

  out=$("${run[@]}" --version)
  [ "$out" = "mavping $version" ] || fail "$target: --version printed '$out', expected 'mavping $version'"
  echo "  --version: $out"

  code=0
  "${run[@]}" --json -q -c 50 -i 0.02 "$sim" >"$work/sim.json" || code=$?
  got="$(json_counts "$work/sim.json" 1/1) / $(json_counts "$work/sim.json" 2/1)"
  [ "$code" = 0 ] || fail "$target: sim: exit $code, expected 0"
  read -r sent1 received1 lost1 _ _ <<<"$(json_counts "$work/sim.json" 1/1)"
  [ "$lost1" -gt 0 ] || fail "$target: the seeded sim loss did not happen"
  case "$target" in
    armv7-* | arm-* | thumbv7* | i686-*)
      # rand's SmallRng is another generator on 32-bit CPUs (Xoshiro128++,
      # not Xoshiro256++), so a seed draws other faults there: the counts
      # must add up, they cannot equal the 64-bit host's.
      [ "$sent1" = 50 ] && [ $((received1 + lost1)) = 50 ] ||
        fail "$target: sim 1/1: $sent1 sent, $received1 received, $lost1 lost do not add up to 50"
      echo "  sim (sent received lost duplicate exit, 1/1 / 2/1): $got (32-bit: its own draws; native $native_sim)"
      ;;
    *)
      [ "$got" = "$native_sim" ] || fail "$target: sim counts '$got' differ from the native '$native_sim'"
      echo "  sim (sent received lost duplicate exit, 1/1 / 2/1): $got, as native"
      ;;
  esac

  code=0
  "${run[@]}" --json -q -c 5 -i 0.02 -W 0.5 'sim:?loss=100%&clock=virtual' >"$work/sim0.json" || code=$?
  [ "$code" = 1 ] || fail "$target: sim with 100% loss: exit $code, expected 1"
  code=0
  "${run[@]}" -c 5 'sim:?loss=abc' >/dev/null 2>"$work/bad.err" || code=$?
  [ "$code" = 2 ] || fail "$target: bad input: exit $code, expected 2"
  grep -q panicked "$work/bad.err" && fail "$target: bad input panicked: $(cat "$work/bad.err")"
  echo "  nothing answers: exit 1; bad input: exit 2 ($(head -1 "$work/bad.err"))"

  # The foreign pinger, the native responder.
  port=$(free_udp_port)
  start_respond "$native" respond --drop 15 --dup 10 --seed 4 "udpin:127.0.0.1:$port"
  code=0
  "${run[@]}" --json -q --probe ping -c $requests -i 0.02 "udpout:localhost:$port" >"$work/ping.json" || code=$?
  stop_respond
  check_udp_counts "foreign pinger -> native respond" $requests

  # The foreign responder, the native pinger.
  port=$(free_udp_port)
  start_respond "${run[@]}" respond --drop 15 --dup 10 --seed 4 "udpin:localhost:$port"
  code=0
  "$native" --json -q --probe ping -c $requests -i 0.02 "udpout:127.0.0.1:$port" >"$work/ping.json" || code=$?
  stop_respond
  check_udp_counts "native pinger -> foreign respond" $requests
done
echo "cross-test: all passed (${targets[*]%%=*})"
