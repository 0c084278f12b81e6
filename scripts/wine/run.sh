#!/usr/bin/env bash
# Runs a Windows .exe under Wine with the ProcessPrng stand-in beside it
# (processprng.c): cargo's runner for x86_64-pc-windows-gnu in
# scripts/windows.sh (CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER).
set -euo pipefail
exe=$1
shift
dll="$(dirname "$exe")/bcryptprimitives.dll"
[ -f "$dll" ] || cp "${MAVPING_WINE_SHIM:?built by scripts/windows.sh}" "$dll"
export WINEDEBUG=${WINEDEBUG:--all}
exec "${WINE:-/usr/lib/wine/wine64}" "$exe" "$@"
