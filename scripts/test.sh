#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: puts pymavlink (the
# third-party MAVLink peer the interop tests use) and pyserial (which
# pymavlink needs to open a serial port) in .venv, the Prometheus server
# and promtool, and tmux, then cargo test.
set -euo pipefail
cd "$(dirname "$0")/.."

PYMAVLINK_VERSION=2.4.50
PYSERIAL_VERSION=3.5
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import pymavlink, serial" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check \
    "pymavlink==${PYMAVLINK_VERSION}" "pyserial==${PYSERIAL_VERSION}"
fi
# Debian's prometheus package: the server scrapes `mavping serve` in an
# integration test, and promtool checks expositions and unit-tests the
# alerting rules in contrib/. tmux runs --live in a real terminal.
# Installed only when missing.
missing=()
{ command -v prometheus && command -v promtool; } >/dev/null || missing+=(prometheus)
command -v tmux >/dev/null || missing+=(tmux)
if [ ${#missing[@]} -gt 0 ]; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
export MAVPING_PYTHON="$PWD/.venv/bin/python"
cargo test --all-targets "$@"
