#!/usr/bin/env bash
# Builds mavping's Debian package from one binary and the repository's
# files, with plain dpkg-deb (no cargo-deb, nothing downloaded):
#
#   bash scripts/deb.sh --binary PATH --arch amd64|arm64|armhf --version V --out DIR
#
# writes DIR/mavping_V_ARCH.deb. Release packages are made by
# scripts/dist.sh from the static musl binaries, so they need no libc of
# any version and declare no Depends; tests/it/deb.rs packs its own
# (dynamic) test binary the same way.
#
# Options: --compression xz|gzip|none (default xz, which every dpkg
# reads; the test packs a 100 MB debug binary with none), --maintainer
# 'NAME <EMAIL>' (default: Cargo.toml's first author, or the placeholder
# below).
# SOURCE_DATE_EPOCH (default: the last commit's time) fixes every
# timestamp, so two runs on one tree give the same bytes.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() {
  echo "usage: bash scripts/deb.sh --binary PATH --arch amd64|arm64|armhf --version V --out DIR [--compression xz|gzip|none] [--maintainer 'NAME <EMAIL>']" >&2
  exit 2
}
die() {
  echo "deb.sh: $*" >&2
  exit 2
}

binary="" arch="" version="" out="" compression=xz maintainer=""
while [ $# -gt 0 ]; do
  case "$1" in
    --binary) binary=${2-}; shift 2 || usage ;;
    --arch) arch=${2-}; shift 2 || usage ;;
    --version) version=${2-}; shift 2 || usage ;;
    --out) out=${2-}; shift 2 || usage ;;
    --compression) compression=${2-}; shift 2 || usage ;;
    --maintainer) maintainer=${2-}; shift 2 || usage ;;
    -h|--help) usage ;;
    *) die "unknown argument '$1'" ;;
  esac
done
[ -n "$binary" ] && [ -n "$arch" ] && [ -n "$version" ] && [ -n "$out" ] || usage
command -v dpkg-deb >/dev/null || die "dpkg-deb is missing (Debian's dpkg package)"

# What each Debian architecture's ELF header says (e_machine, at byte 18):
# a binary packed under the wrong one would install and never run.
case "$arch" in
  amd64) machine=3e00 ;;
  arm64) machine=b700 ;;
  armhf) machine=2800 ;;
  *) die "--arch $arch: expected amd64, arm64 or armhf" ;;
esac
[ -f "$binary" ] && [ -x "$binary" ] || die "--binary $binary: no such executable"
[ "$(head -c 4 "$binary" | od -An -tx1 | tr -d ' \n')" = 7f454c46 ] ||
  die "--binary $binary: not an ELF executable"
found=$(od -An -tx1 -j18 -N2 "$binary" | tr -d ' \n')
[ "$found" = "$machine" ] || die "--binary $binary: its ELF machine is $found, not $arch's $machine"
# Debian's version syntax: upstream [A-Za-z0-9.+~-], starting with a digit.
[[ "$version" =~ ^[0-9][A-Za-z0-9.+~-]*$ ]] ||
  die "--version $version: not a Debian version (a digit first, then letters, digits, . + ~ -)"
case "$compression" in xz|gzip|none) ;; *) die "--compression $compression: expected xz, gzip or none" ;; esac
if [ -z "$maintainer" ]; then
  maintainer=$(sed -n 's/^authors *= *\[ *"\([^"]*\)".*/\1/p' Cargo.toml | head -n1)
fi
# A placeholder until Cargo.toml names the authors; .invalid never routes.
maintainer=${maintainer:-The mavping developers <mavping@maintainers.invalid>}
homepage=$(sed -n 's/^homepage *= *"\([^"]*\)".*/\1/p' Cargo.toml | head -n1)
homepage=${homepage:-$(sed -n 's/^repository *= *"\([^"]*\)".*/\1/p' Cargo.toml | head -n1)}
homepage=${homepage:-https://crates.io/crates/mavping}
export SOURCE_DATE_EPOCH=${SOURCE_DATE_EPOCH:-$(git log -1 --format=%ct 2>/dev/null || date +%s)}

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
root="$stage/mavping"
doc="$root/usr/share/doc/mavping"

# Files, each with its mode: dpkg-deb packs what is on disk.
put() { install -D -m "$1" "$2" "$root/$3"; }
put 0755 "$binary" usr/bin/mavping
for page in mavping.1 mavping-respond.1 mavping-compare.1; do
  install -d -m 0755 "$root/usr/share/man/man1"
  gzip -9n < "completions/$page" > "$root/usr/share/man/man1/$page.gz"
done
put 0644 completions/mavping.bash usr/share/bash-completion/completions/mavping
put 0644 completions/_mavping usr/share/zsh/vendor-completions/_mavping
put 0644 completions/mavping.fish usr/share/fish/vendor_completions.d/mavping.fish
put 0644 packaging/debian/serve.toml etc/mavping/serve.toml
put 0644 packaging/debian/web.yml etc/mavping/web.yml
put 0644 packaging/debian/mavping-serve.service usr/lib/systemd/system/mavping-serve.service
put 0644 packaging/debian/copyright usr/share/doc/mavping/copyright
put 0644 docs/service.md usr/share/doc/mavping/service.md
put 0644 README.md usr/share/doc/mavping/README.md
for f in contrib/mavping-serve.toml contrib/prometheus/mavping.rules.yml \
  contrib/prometheus/mavping.rules.test.yml contrib/prometheus/prometheus.yml \
  contrib/grafana/mavping-dashboard.json; do
  put 0644 "$f" "usr/share/doc/mavping/examples/$(basename "$f")"
done
gzip -9n < CHANGELOG.md > "$doc/changelog.gz"
chmod 0644 "$doc/changelog.gz"
{
  echo "mavping ($version) unstable; urgency=medium"
  echo
  echo "  * Upstream release $version: see /usr/share/doc/mavping/changelog.gz."
  echo
  echo " -- $maintainer  $(LC_ALL=C date -u -R -d "@$SOURCE_DATE_EPOCH")"
} | gzip -9n > "$doc/changelog.Debian.gz"
chmod 0644 "$doc/changelog.Debian.gz"

# The control area: the conffile is the operator's, kept across upgrades
# and removed only by a purge. No maintainer scripts: the service is
# installed and left disabled, the operator enables it.
install -d -m 0755 "$root/DEBIAN"
printf '%s\n' /etc/mavping/serve.toml /etc/mavping/web.yml > "$root/DEBIAN/conffiles"
(cd "$root" && find . -path ./DEBIAN -prune -o -path ./etc -prune -o -type f -printf '%P\n' |
  LC_ALL=C sort | xargs md5sum) > "$root/DEBIAN/md5sums"
size=$(du -sk --exclude=DEBIAN "$root" | cut -f1)
cat > "$root/DEBIAN/control" <<EOF
Package: mavping
Version: $version
Architecture: $arch
Maintainer: $maintainer
Installed-Size: $size
Section: net
Priority: optional
Homepage: $homepage
Description: measure MAVLink links: latency, loss and a Prometheus exporter
 mavping measures MAVLink links (UDP, TCP, serial) as ping measures IP
 ones: PING, TIMESYNC and command probes with exact loss, duplicate and
 RTT figures, passive listening to a vehicle's own telemetry, telemetry
 logs, sweeps, and mavping serve, a Prometheus exporter for a fleet.
 .
 This package holds a static binary, its man pages and completions, and
 mavping-serve.service (installed, not enabled), with the configuration
 in /etc/mavping/serve.toml and Prometheus and Grafana examples.
EOF
find "$root" -exec touch -h -d "@$SOURCE_DATE_EPOCH" {} +
find "$root" -type d -exec chmod 0755 {} +
chmod 0644 "$root/DEBIAN/control" "$root/DEBIAN/conffiles" "$root/DEBIAN/md5sums"

mkdir -p "$out"
deb="$out/mavping_${version}_${arch}.deb"
dpkg-deb --root-owner-group -Z"$compression" --build "$root" "$deb" >/dev/null
echo "$deb"
