#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: puts the third-party MAVLink
# peers the interop tests use in .venv — pymavlink (and pyserial, which it
# needs to open a serial port), MAVProxy, and MAVSDK's mavsdk_server (the
# static binary inside the mavsdk-grpc wheel) — installs the Prometheus
# server and promtool, tmux, man and the DejaVu fonts, then runs cargo test.
set -euo pipefail
cd "$(dirname "$0")/.."

PYMAVLINK_VERSION=2.4.50
PYSERIAL_VERSION=3.5
MAVPROXY_VERSION=1.8.75
MAVSDK_GRPC_VERSION=4.0.5
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import pymavlink, serial" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/python -m pip install --quiet --disable-pip-version-check \
    "pymavlink==${PYMAVLINK_VERSION}" "pyserial==${PYSERIAL_VERSION}"
fi
# MAVProxy's console and map modules pull in OpenCV, wxPython and
# matplotlib (over 1 GB); the router and its system_time module need only
# pymavlink, so it is installed without its dependencies. mavsdk-grpc is
# wanted for its mavsdk_server binary only.
site=$(.venv/bin/python -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
if [ ! -x .venv/bin/mavproxy.py ]; then
  .venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps "MAVProxy==${MAVPROXY_VERSION}"
fi
if [ ! -x "$site/mavsdk_grpc/bin/mavsdk_server" ]; then
  .venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps "mavsdk-grpc==${MAVSDK_GRPC_VERSION}"
fi
# Debian's prometheus package: the server scrapes `mavping serve` in an
# integration test, and promtool checks expositions and unit-tests the
# alerting rules in contrib/. tmux runs --live in a real terminal; man
# renders the man pages; resvg renders --plot's text in DejaVu Sans.
# Installed only when missing.
missing=()
{ command -v prometheus && command -v promtool; } >/dev/null || missing+=(prometheus)
command -v tmux >/dev/null || missing+=(tmux)
# tc and ip make the token-bucket queue in a network namespace that the
# sweep's kernel-queue test measures.
{ command -v tc && command -v ip; } >/dev/null || missing+=(iproute2)
# man renders the committed man pages in a test (man-db brings groff).
command -v man >/dev/null || missing+=(man-db)
[ -f /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || missing+=(fonts-dejavu-core)
if [ ${#missing[@]} -gt 0 ]; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
export MAVPING_PYTHON="$PWD/.venv/bin/python"
cargo test --all-targets "$@"
# The portable path (what Windows and macOS get: build.rs) on Linux, so it
# cannot rot: the UDP, TCP, serial (pty) and sim: tests again, against a
# build with --features portable (and its one-line -I refusal).
if [ $# -eq 0 ]; then
  cargo test --features portable --test it -- \
    udp_pymavlink:: tcp_pymavlink:: serial_pty:: sim_soak:: udp_bcast_ipv6:: \
    multilink:: stalled:: habits::dash_i
fi
