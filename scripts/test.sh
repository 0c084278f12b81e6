#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: puts the third-party MAVLink
# peers the interop tests use in .venv — pymavlink (and pyserial, which it
# needs to open a serial port), MAVProxy, MAVSDK's mavsdk_server (the
# static binary inside the mavsdk-grpc wheel) and MAVSDK's C++ library
# with its Python binding (the mavsdk wheel) — installs the Prometheus
# server and promtool, tmux, man, systemd's tools and the DejaVu fonts,
# then runs cargo test.
set -euo pipefail
cd "$(dirname "$0")/.."

PYMAVLINK_VERSION=2.4.50
PYSERIAL_VERSION=3.5
MAVPROXY_VERSION=1.8.75
MAVSDK_GRPC_VERSION=4.0.5
MAVSDK_VERSION=4.1.0
WSPROTO_VERSION=1.3.2
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import pymavlink, serial" 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/python -m pip install --quiet --disable-pip-version-check \
    "pymavlink==${PYMAVLINK_VERSION}" "pyserial==${PYSERIAL_VERSION}"
fi
# MAVProxy's console and map modules pull in OpenCV, wxPython and
# matplotlib (over 1 GB); the router and its system_time module need only
# pymavlink, so it is installed without its dependencies. mavsdk-grpc is
# wanted for its mavsdk_server binary only. mavsdk (4.x, a different
# package: the ctypes binding around libcmavsdk.so, no Python dependencies,
# its own top-level module beside mavsdk_grpc) drives MAVSDK's parameter,
# mission and FTP servers in tests/peers/mavsdk_vehicle.py.
site=$(.venv/bin/python -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
if [ ! -x .venv/bin/mavproxy.py ]; then
  .venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps "MAVProxy==${MAVPROXY_VERSION}"
fi
if [ ! -x "$site/mavsdk_grpc/bin/mavsdk_server" ]; then
  .venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps "mavsdk-grpc==${MAVSDK_GRPC_VERSION}"
fi
if [ ! -f "$site/mavsdk/lib/libcmavsdk.so" ]; then
  .venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps "mavsdk==${MAVSDK_VERSION}"
fi
# wsproto: pymavlink's own WebSocket server and client (wsserver:, ws:)
# need it, and so does tests/peers/ws_peer.py.
if ! .venv/bin/python -c "import wsproto" 2>/dev/null; then
  .venv/bin/python -m pip install --quiet --disable-pip-version-check "wsproto==${WSPROTO_VERSION}"
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
# systemd-analyze and systemctl check the Debian package's unit in
# tests/it/deb.rs (the package boots nothing; dpkg is always there).
command -v systemd-analyze >/dev/null || missing+=(systemd)
[ -f /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || missing+=(fonts-dejavu-core)
# curl and openssl drive the TLS tests of `serve --web.config.file` (client
# certificates, reload); clang and llvm-ar cross-compile ring's C for the musl
# and Apple targets (.cargo/config.toml).
command -v curl >/dev/null || missing+=(curl)
command -v openssl >/dev/null || missing+=(openssl)
# socat's OPENSSL-LISTEN is the TLS terminator in front of pymavlink's
# WebSocket server for the wss:// tests.
command -v socat >/dev/null || missing+=(socat)
{ command -v clang && command -v llvm-ar; } >/dev/null || missing+=(clang llvm)
# qemu-aarch64 runs the aarch64 build (below).
command -v qemu-aarch64 >/dev/null || missing+=(qemu-user)
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

# The whole suite (no arguments) also builds mavping for aarch64, a
# companion computer's CPU, and runs it under qemu-aarch64 against the host
# build (scripts/cross-test.sh: the simulated link's counts, both ends of a
# UDP run, exit codes). In the dev profile, which builds in a fraction of
# dist's time, and in a target directory kept in ~/.cache per Cargo.lock, so
# that only mavping itself is compiled again while the dependencies stay.
if [ $# -eq 0 ]; then
  cross=aarch64-unknown-linux-musl
  rustup target list --installed | grep -qx "$cross" || rustup target add "$cross"
  cache=${XDG_CACHE_HOME:-$HOME/.cache}/mavping
  key=cross-$(sha256sum Cargo.lock | cut -c1-16)
  mkdir -p "$cache"
  find "$cache" -mindepth 1 -maxdepth 1 -name 'cross-*' ! -name "$key" -exec rm -rf {} +
  cargo build --locked --target "$cross" --target-dir "$cache/$key"
  bash scripts/cross-test.sh --target-dir "$cache/$key" --profile debug "$cross"
fi
