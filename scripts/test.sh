#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: puts pymavlink (the
# third-party MAVLink peer the interop tests use) and pyserial (which
# pymavlink needs to open a serial port) in .venv, then cargo test.
set -euo pipefail
cd "$(dirname "$0")/.."

PYMAVLINK_VERSION=2.4.50
PYSERIAL_VERSION=3.5
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import pymavlink, serial" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check \
    "pymavlink==${PYMAVLINK_VERSION}" "pyserial==${PYSERIAL_VERSION}"
fi
export MAVPING_PYTHON="$PWD/.venv/bin/python"
cargo test --all-targets "$@"
