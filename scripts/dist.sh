#!/usr/bin/env bash
# Builds what a release ships, in dist/:
#   mavping-VERSION-TARGET.tar.gz   the static binary, man pages, completions,
#                                   LICENSE, README, CHANGELOG
#   mavping_VERSION_ARCH.deb        (scripts/deb.sh, when it is there)
#   mavping_cli-VERSION-*.whl       the binary as a Python wheel (maturin)
#   mavping-VERSION-x86_64-pc-windows-gnu.zip
#                                   mavping.exe, tested under Wine first
#                                   (scripts/windows.sh --zip)
#   SHA256SUMS
# and checks the crate as crates.io builds it (`cargo publish --dry-run`,
# verified: a dev build of the packaged sources; --no-publish-check skips it).
# for x86_64, aarch64 and 32-bit ARM Linux, every binary static (no libc
# needed on the board), built in the size-tuned `dist` profile. Every
# foreign binary is run under qemu-user (scripts/cross-test.sh), and the
# x86_64 wheel is installed into a fresh venv and run.
#
# Usage: scripts/dist.sh [--no-publish-check] [--no-windows] [TARGET...]
# Installs what it lacks: rustup targets (rustup), qemu-user, the ARM cross
# linker and gcc file (apt-get, as root), maturin (pip, in target/dist-venv).
# Nothing else is downloaded. Idempotent: a second run rebuilds nothing
# that is up to date and writes dist/ again. See docs/install.md.
set -euo pipefail
cd "$(dirname "$0")/.."

MATURIN_VERSION=1.16.0
# A static Linux binary may be at most 5 MB (10^6 bytes each).
MAX_BYTES=5000000
default_targets=(
  x86_64-unknown-linux-musl
  aarch64-unknown-linux-musl
  # 32-bit Raspberry Pi OS: armv7-unknown-linux-musleabihf's standard
  # library is not on the rustup mirror this was made with, so glibc's,
  # linked statically (.cargo/config.toml); see docs/install.md.
  armv7-unknown-linux-gnueabihf
)
publish_check=1
windows=1
while [ $# -gt 0 ]; do
  case "$1" in
    --no-publish-check) publish_check=0 ;;
    --no-windows) windows=0 ;;
    *) break ;;
  esac
  shift
done
[ $# -gt 0 ] && targets=("$@") || targets=("${default_targets[@]}")
version=$(sed -nE 's/^version = "(.*)"/\1/p' Cargo.toml | head -1)
out=dist

say() { printf '\n== dist: %s\n' "$*"; }
die() {
  echo "dist: FAIL: $*" >&2
  exit 1
}

# Debian packages, installed once when missing (a lock, as several builds
# may share a machine).
apt_install() {
  [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null ||
    die "needs the Debian packages $* (apt-get install $*)"
  local lock=()
  command -v flock >/dev/null && lock=(flock /tmp/apt.lock)
  if ! "${lock[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@"; then
    "${lock[@]}" apt-get update -qq
    "${lock[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@"
  fi
}

install_tools() {
  local installed t
  installed=$(rustup target list --installed)
  for t in "${targets[@]}"; do
    grep -qx "$t" <<<"$installed" || rustup target add "$t"
  done
  command -v file >/dev/null || apt_install file
  { command -v qemu-aarch64 && command -v qemu-arm; } >/dev/null || apt_install qemu-user
  if printf '%s\n' "${targets[@]}" | grep -q '^armv7-unknown-linux-gnueabihf$'; then
    command -v arm-linux-gnueabihf-gcc >/dev/null && [ -f /usr/arm-linux-gnueabihf/lib/libc.a ] ||
      apt_install gcc-arm-linux-gnueabihf libc6-dev-armhf-cross
  fi
  if [ ! -x target/dist-venv/bin/maturin ] ||
    [ "$(target/dist-venv/bin/maturin --version)" != "maturin $MATURIN_VERSION" ]; then
    python3 -m venv target/dist-venv || { apt_install python3-venv && python3 -m venv target/dist-venv; }
    target/dist-venv/bin/python -m pip install --quiet --disable-pip-version-check "maturin==$MATURIN_VERSION"
  fi
}

# A target directory per target: one target's build never waits on
# another's lock, so they may also be built at once by hand.
target_dir() { echo "target/dist-build/$1"; }
binary() { echo "$(target_dir "$1")/$1/dist/mavping"; }

build() {
  local t bin kind
  for t in "${targets[@]}"; do
    say "cargo build --profile dist --target $t"
    cargo build --locked --profile dist --target "$t" --target-dir "$(target_dir "$t")"
    bin=$(binary "$t")
    # Static or it does not run on an older system than this one.
    kind=$(file -b "$bin")
    grep -Eq 'statically linked|static-pie linked' <<<"$kind" || die "$bin is not static: $kind"
    size=$(stat -c %s "$bin")
    echo "$bin: $size bytes; $kind"
    # The promise to companion computers (issue 29): at most 5 MB.
    [ "$size" -le "$MAX_BYTES" ] || die "$bin is $size bytes, over the $MAX_BYTES-byte goal"
  done
}

# The native end of the foreign binaries' runs: the x86_64 build when there
# is one, else a debug build.
native_binary() {
  if printf '%s\n' "${targets[@]}" | grep -q '^x86_64-unknown-linux-musl$'; then
    binary x86_64-unknown-linux-musl
  else
    cargo build --locked --quiet
    echo target/debug/mavping
  fi
}

archive() {
  local t=$1 name="mavping-$version-$1" stage
  stage=$(mktemp -d)
  mkdir -p "$stage/$name/man" "$stage/$name/completions"
  cp "$(binary "$t")" "$stage/$name/mavping"
  cp completions/mavping.1 completions/mavping-respond.1 completions/mavping-compare.1 "$stage/$name/man/"
  cp completions/mavping.bash completions/_mavping completions/mavping.fish \
    completions/_mavping.ps1 completions/mavping.elv "$stage/$name/completions/"
  cp LICENSE README.md CHANGELOG.md "$stage/$name/"
  # Reproducible: same names, owners and times from one commit.
  tar -C "$stage" --sort=name --owner=0 --group=0 --numeric-owner \
    --mtime="@$(git log -1 --format=%ct)" -cf - "$name" | gzip -9n >"$out/$name.tar.gz"
  rm -rf "$stage"
}

deb_arch() {
  case "$1" in
    x86_64-*) echo amd64 ;;
    aarch64-*) echo arm64 ;;
    armv7-*) echo armhf ;;
    *) die "no Debian architecture for $1" ;;
  esac
}

debs() {
  if [ ! -f scripts/deb.sh ]; then
    echo "##################################################################" >&2
    echo "## dist: SKIPPING the .deb packages: scripts/deb.sh is not here  ##" >&2
    echo "##################################################################" >&2
    return 0
  fi
  local t
  for t in "${targets[@]}"; do
    say "scripts/deb.sh $(deb_arch "$t")"
    bash scripts/deb.sh --binary "$(binary "$t")" --arch "$(deb_arch "$t")" --version "$version" --out "$out/"
  done
}

# maturin's `bin` bindings, from the static musl builds: one wheel installs on
# glibc (manylinux) and musl (musllinux) systems alike.
wheels() {
  local t
  for t in "${targets[@]}"; do
    case "$t" in *-musl) ;; *) continue ;; esac
    say "maturin build --target $t"
    CARGO_TARGET_DIR=$(target_dir "$t") target/dist-venv/bin/maturin build --locked --profile dist --target "$t" \
      --compatibility manylinux2014 musllinux_1_2 --out "$out"
  done
}

# The x86_64 wheel as a user gets it: a fresh venv, pip install, run.
test_wheel() {
  local wheel venv code=0
  wheel=$(ls "$out"/mavping_cli-"$version"-*x86_64*.whl 2>/dev/null | head -1)
  [ -n "$wheel" ] || return 0
  venv=$(mktemp -d)
  say "pip install $wheel into a fresh venv"
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-index "$wheel"
  [ "$("$venv/bin/mavping" --version)" = "mavping $version" ] || die "the wheel's mavping --version is wrong"
  "$venv/bin/mavping" -c 5 -i 0.2 sim: >"$venv/run.txt" || code=$?
  [ "$code" = 0 ] && grep -q '5 sent, 5 received, 0 lost' "$venv/run.txt" ||
    die "the wheel's mavping sim: -c 5 exited $code: $(cat "$venv/run.txt")"
  echo "$venv/bin/mavping --version: mavping $version; mavping -c 5 -i 0.2 sim: exit 0:"
  grep ' sent, ' "$venv/run.txt"
  rm -rf "$venv"
}

# The Windows zip: windows.sh checks mavping.exe under Wine (unit tests,
# sim:, UDP counts, exit codes, completions) before it packs the dist build.
windows_zip() {
  [ "$windows" = 1 ] || { echo "dist: Windows zip skipped (--no-windows)"; return 0; }
  say "scripts/windows.sh --zip"
  bash scripts/windows.sh --zip
  cp "target/dist/mavping-$version-x86_64-pc-windows-gnu.zip" "$out/"
}

sums() {
  (cd "$out" && sha256sum -- *.tar.gz $(ls -- *.deb *.whl *.zip 2>/dev/null) >SHA256SUMS)
  say "dist/ (bytes, SHA-256)"
  local f
  while read -r sum f; do
    printf '%10s  %s  %s\n' "$(stat -c %s "$out/$f")" "$sum" "$f"
  done <"$out/SHA256SUMS"
  for t in "${targets[@]}"; do
    printf '%10s  %s\n' "$(stat -c %s "$(binary "$t")")" "$(binary "$t")"
  done
}

# What `cargo install --locked mavping` will build, before it is published.
publish_check() {
  [ "$publish_check" = 1 ] || { echo "dist: publish check skipped (--no-publish-check)"; return 0; }
  say "cargo publish --dry-run --locked"
  cargo publish --dry-run --locked
}

install_tools
build
say "scripts/cross-test.sh (qemu-user for the foreign CPUs)"
tested=()
for t in "${targets[@]}"; do tested+=("$t=$(binary "$t")"); done
bash scripts/cross-test.sh --native "$(native_binary)" "${tested[@]}"
rm -rf "$out"
mkdir -p "$out"
for t in "${targets[@]}"; do archive "$t"; done
debs
wheels
test_wheel
windows_zip
sums
publish_check
