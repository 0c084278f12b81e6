#!/usr/bin/env bash
# Windows, tested under Wine (Debian 12's wine64 8.0, MinGW-w64 as the
# linker, .cargo/config.toml): cross-builds mavping.exe
# (x86_64-pc-windows-gnu), runs the library's unit tests under Wine, then
# mavping.exe itself: `sim:`, a UDP run against `mavping.exe respond` on
# loopback with exact counts from the JSON summary, the exit codes of a
# silent link, a bad address and -I (Linux only), and that mavping.exe
# accepts every option its PowerShell completions offer.
#
#   scripts/windows.sh          the checks above
#   scripts/windows.sh --zip    also target/dist/mavping-VERSION-x86_64-pc-windows-gnu.zip
#                               (dist profile: binary, LICENSE, README, completions),
#                               for scripts/dist.sh
#
# Wine 8 lacks ProcessPrng, which Rust's std imports: scripts/wine/processprng.c
# is built as bcryptprimitives.dll and copied beside each .exe for these runs
# only (never into the zip; real Windows has the DLL).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_BUILD_JOBS=${CARGO_BUILD_JOBS:-1}
TARGET=x86_64-pc-windows-gnu
WINE=${WINE:-/usr/lib/wine/wine64}
zip=false
[ "${1:-}" = --zip ] && zip=true

# What it needs, installed when missing.
missing=()
command -v x86_64-w64-mingw32-gcc >/dev/null || missing+=(gcc-mingw-w64-x86-64)
[ -x "$WINE" ] || missing+=(wine64)
if [ ${#missing[@]} -gt 0 ]; then
  flock /tmp/apt.lock apt-get update -qq
  DEBIAN_FRONTEND=noninteractive flock /tmp/apt.lock apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
rustup target list --installed | grep -qx "$TARGET" || rustup target add "$TARGET"

step() { printf '\n== %s\n' "$*"; }
t0=$(date +%s)

step "the ProcessPrng stand-in for Wine"
mkdir -p target/wine
shim=$PWD/target/wine/bcryptprimitives.dll
x86_64-w64-mingw32-gcc -O2 -shared -o "$shim" scripts/wine/processprng.c -ladvapi32
export MAVPING_WINE_SHIM=$shim WINE
export WINEDEBUG=-all
WINEPREFIX=$(mktemp -d /tmp/mavping-wine.XXXXXX)
export WINEPREFIX
cleanup() {
  [ -n "${respond_pid:-}" ] && kill "$respond_pid" 2>/dev/null || true
  rm -rf "$WINEPREFIX"
}
trap cleanup EXIT
runner=$PWD/scripts/wine/run.sh

step "unit tests under Wine (cargo test --lib --target $TARGET)"
CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER=$runner \
  cargo test --quiet --lib --target "$TARGET" 2>&1 | tee target/wine/unit.txt | grep -E '^test result|FAILED|panicked' || true
grep -q '^test result: ok' target/wine/unit.txt || { echo "unit tests failed under Wine"; exit 1; }

step "mavping.exe"
cargo build --quiet --target "$TARGET"
exe=target/$TARGET/debug/mavping.exe
mav() { "$runner" "$exe" "$@"; }
# A field of the last JSON line (the summary).
field() { python3 -c 'import json,sys; s=[json.loads(l) for l in sys.stdin if l.strip()][-1]; print(eval(sys.argv[1], {}, {"s": s}))' "$1"; }

fails=0
check() { # what expected got
  if [ "$2" = "$3" ]; then echo "ok   $1: $3"; else echo "FAIL $1: expected $2, got $3"; fails=$((fails + 1)); fi
}

set +e
out=$(mav --format json -c 50 -i 10ms 'sim:?clock=virtual&loss=10%&seed=7'); rc=$?
set -e
check "sim: exit code" 0 "$rc"
check "sim: requests" 50 "$(field 's["requests"]' <<<"$out")"
# The simulated link's own ground truth: the same seed on the Linux build.
native=$(cargo run --quiet -- --format json -c 50 -i 10ms 'sim:?clock=virtual&loss=10%&seed=7' || true)
check "sim: replies as on Linux (same seed)" \
  "$(field 's["responders"][0]["received"]' <<<"$native")" \
  "$(field 's["responders"][0]["received"]' <<<"$out")"

port=$((20000 + RANDOM % 20000))
mav respond "udpin:127.0.0.1:$port" >target/wine/respond.txt 2>&1 &
respond_pid=$!
sleep 3 # Wine's start, not the responder's
set +e
out=$(mav --format json -c 200 -i 5ms -W 2s "udpout:127.0.0.1:$port"); rc=$?
set -e
check "udp vs respond: exit code" 0 "$rc"
check "udp vs respond: requests" 200 "$(field 's["requests"]' <<<"$out")"
check "udp vs respond: replies" 200 "$(field 's["responders"][0]["received"]' <<<"$out")"
check "udp vs respond: receive clock" "user-space receive timestamps" "$(field 's["rx_clock"]' <<<"$out")"
echo "     rtt p50/max: $(field '"%.0f/%.0f us" % (s["responders"][0]["rtt_us"]["p50"], s["responders"][0]["rtt_us"]["max"])' <<<"$out")"
kill "$respond_pid" 2>/dev/null || true
respond_pid=

set +e
# Nobody at the port: as on Linux, the ICMP refusal ends the run (exit 2,
# one line), and with --reconnect the run goes on, every PING lost (exit 1).
# Bounded by timeout: before udp.rs's unstick() this spun at 100 % CPU
# under Wine (the socket stuck "closed" with nothing to read) and never
# ended.
err=$(timeout 60 "$runner" "$exe" -q -c 3 -i 100ms -W 300ms "udpout:127.0.0.1:$((port + 1))" 2>&1 >/dev/null); rc=$?
check "nobody listening: exit code" 2 "$rc"
check "nobody listening: the refusal named" 1 "$(grep -c 'nothing listening at 127.0.0.1' <<<"$err")"
out=$(timeout 60 "$runner" "$exe" --reconnect --format json -c 3 -i 100ms -W 300ms "udpout:127.0.0.1:$((port + 1))"); rc=$?
check "nobody listening, --reconnect: exit code" 1 "$rc"
check "nobody listening, --reconnect: requests" 3 "$(field 's["requests"]' <<<"$out")"
err=$(mav -c 1 carrier-pigeon:1:2 2>&1 >/dev/null); rc=$?
check "bad address: exit code" 2 "$rc"
check "bad address: one line" 1 "$(printf '%s\n' "$err" | tr -d '\r' | grep -c .)"
err=$(mav -I eth0 -c 1 "udpout:127.0.0.1:$port" 2>&1 >/dev/null); rc=$?
check "-I off Linux: exit code" 2 "$rc"
check "-I off Linux: one line" 1 "$(printf '%s\n' "$err" | tr -d '\r' | grep -c .)"
echo "     $err"
set -e

step "what the PowerShell completions offer, mavping.exe accepts"
# completions/_mavping.ps1 asks the program itself (COMPLETE=powershell):
# every option and subcommand it offers must be one --help lists, and
# each subcommand must parse.
help=$(mav --help | tr -d '\r')
offered=$(COMPLETE=powershell mav -- mavping -- | tr -d '\r' | cut -f1)
# Subcommands only: the offer for an empty word also lists options and
# the connection-string schemes.
subs=$(COMPLETE=powershell mav -- mavping '' | tr -d '\r' | cut -f1 | grep -v ':$' | grep -v '^-' | grep -v '^help$' || true)
n=0
for opt in $offered; do
  n=$((n + 1))
  grep -q -- "$opt\b" <<<"$help" || { echo "FAIL offered $opt, not in --help"; fails=$((fails + 1)); }
done
for sub in $subs; do
  n=$((n + 1))
  mav "$sub" --help >/dev/null 2>&1 || { echo "FAIL offered subcommand $sub does not parse"; fails=$((fails + 1)); }
  for opt in $(COMPLETE=powershell mav -- mavping "$sub" -- | tr -d '\r' | cut -f1); do
    n=$((n + 1))
    mav "$sub" --help | tr -d '\r' | grep -q -- "$opt\b" || { echo "FAIL $sub: offered $opt, not in its --help"; fails=$((fails + 1)); }
  done
done
native_offered=$(COMPLETE=powershell cargo run --quiet -- -- mavping -- | cut -f1)
check "offered options as on Linux" "$(sort <<<"$native_offered" | tr '\n' ' ')" "$(sort <<<"$offered" | tr '\n' ' ')"
echo "     $n offered names checked ($(wc -w <<<"$subs") subcommands)"

if $zip; then
  step "the release zip"
  cargo build --quiet --profile dist --target "$TARGET"
  version=$(cargo metadata --no-deps --format-version 1 | python3 -c 'import json,sys; print(json.load(sys.stdin)["packages"][0]["version"])')
  name=mavping-$version-$TARGET
  stage=$(mktemp -d)
  mkdir -p "$stage/$name" target/dist
  cp "target/$TARGET/dist/mavping.exe" LICENSE README.md "$stage/$name/"
  cp -r completions "$stage/$name/"
  rm -f "target/dist/$name.zip"
  (cd "$stage" && python3 -m zipfile -c "$OLDPWD/target/dist/$name.zip" "$name")
  rm -rf "$stage"
  # The zipped binary runs (with the stand-in beside it, here only).
  unz=$(mktemp -d)
  python3 -m zipfile -e "target/dist/$name.zip" "$unz"
  check "zipped mavping.exe runs" 0 "$("$runner" "$unz/$name/mavping.exe" -q -c 3 -i 10ms 'sim:?clock=virtual' >/dev/null 2>&1; echo $?)"
  rm -rf "$unz"
  ls -l "target/dist/$name.zip"
fi

echo
echo "windows.sh: $fails failed, $(( $(date +%s) - t0 )) s"
[ "$fails" -eq 0 ]
