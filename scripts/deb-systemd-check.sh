#!/usr/bin/env bash
# Runs mavping-serve.service under a real systemd on a machine whose PID 1
# is not systemd (a container, a CI VM): installs the .deb, boots systemd
# as PID 1 of new pid, mount, network, UTS, IPC and cgroup namespaces with
# only the service (its own /run, /tmp, journal and cgroup2 mounts, a
# network of loopback only), and checks the sandboxed exporter works: a
# continuous UDP link to `mavping respond`, a udpbcast: link (netlink), a
# serial link over a pty given to group dialout, a /probe, a reload. Then
# it stops that systemd, purges the package and removes its cgroups.
#
#   sudo bash scripts/deb-systemd-check.sh [BINARY]    (default target/debug/mavping)
#
# Needs root with CAP_SYS_ADMIN, systemd, python3, curl, unshare and
# nsenter. Not in CI: it boots an init. Figures are in docs/service.md.
set -euo pipefail
cd "$(dirname "$0")/.."
binary=${1:-target/debug/mavping}
work=$(mktemp -d /var/tmp/mavping-systemd-check.XXXXXX)
touch "$work/deb"
sd=""

cleanup() {
  if [ -n "$sd" ]; then
    # Stopped first, so systemd removes the service's private /var/tmp.
    nsenter -t "$sd" -m -p -n -u -i systemctl stop mavping-serve 2>/dev/null || true
    kill -9 "$sd" 2>/dev/null || true
    sleep 1
  fi
  dpkg --purge mavping >/dev/null 2>&1 || true
  for d in /sys/fs/cgroup/unified /sys/fs/cgroup; do
    if [ -d "$d/system.slice" ] && [ "$(stat -f -c %T "$d")" = cgroup2fs ]; then
      find "$d/system.slice" -depth -type d -exec rmdir {} \; 2>/dev/null || true
      rmdir "$d/init.scope" 2>/dev/null || true
    fi
  done
  # PID 1 was killed: the service's private /var/tmp stays behind.
  find /var/tmp -maxdepth 1 -name 'systemd-private-*-mavping-serve.service-*' \
    -newer "$work/deb" -exec rm -rf {} + 2>/dev/null || true
  rm -rf "$work"
}
if dpkg-query -W mavping >/dev/null 2>&1 && dpkg-query -W -f='${db:Status-Status}' mavping | grep -qv not-installed; then
  echo "deb-systemd-check: a mavping package is installed; purge it first" >&2
  exit 2
fi
trap cleanup EXIT

arch=$(dpkg --print-architecture)
deb=$(bash scripts/deb.sh --binary "$binary" --arch "$arch" --version 0.0.0~systemd-check \
  --compression none --out "$work")
dpkg -i "$deb" >/dev/null

# Two ptys whose masters are joined; the first given to group dialout.
cat > "$work/ptys.py" <<'EOF'
import grp, os, select
m1, s1 = os.openpty(); m2, s2 = os.openpty()
p1, p2 = os.ttyname(s1), os.ttyname(s2)
os.chown(p1, 0, grp.getgrnam("dialout").gr_gid); os.chmod(p1, 0o660)
print(p1, p2, flush=True)
while True:
    for m in select.select([m1, m2], [], [])[0]:
        os.write(m2 if m == m1 else m1, os.read(m, 4096))
EOF
cat > "$work/serve.toml" <<'EOF'
listen = "127.0.0.1:9465"
allow = ["udpout:127.0.0.1:*"]
[[link]]
link = "udpout:127.0.0.1:14560"
name = "udp"
[[link]]
link = "udpbcast:127.255.255.255:14561"
name = "broadcast"
EOF
chmod 0644 "$work/serve.toml"

# PID 1's world: the config bound over the conffile, private /run, /tmp
# and journal, a cgroup2 hierarchy of its own namespace, and a target
# that starts the service alone (DefaultDependencies=no: no udev, no
# sysctl, nothing of sysinit.target touching the host).
cat > "$work/init.sh" <<EOF
set -euo pipefail
mount --make-rprivate /
mount -t proc proc /proc
mount --bind $work/serve.toml /etc/mavping/serve.toml
mount -t tmpfs tmpfs /run
mount -t tmpfs tmpfs /tmp
[ -d /var/log/journal ] && mount -t tmpfs tmpfs /var/log/journal
umount -l /sys/fs/cgroup
mount -t cgroup2 cgroup2 /sys/fs/cgroup
ip link set lo up
mkdir -p /run/systemd/system/mavping-serve.service.d
printf '[Unit]\nDefaultDependencies=no\nAllowIsolate=yes\nWants=mavping-serve.service\n' \
  > /run/systemd/system/mavping-check.target
printf '[Unit]\nDefaultDependencies=no\n' > /run/systemd/system/mavping-serve.service.d/check.conf
export container=mavping-check
exec /lib/systemd/systemd --system --unit=mavping-check.target --log-target=kmsg --show-status=no
EOF
(unshare --pid --fork --mount --net --uts --ipc --cgroup bash "$work/init.sh" 2>/dev/null &)
for _ in $(seq 100); do
  sd=$(pgrep -f -n "systemd --system --unit=mavping-check.target" || true)
  [ -n "$sd" ] && break
  sleep 0.1
done
[ -n "$sd" ] || { echo "deb-systemd-check: systemd did not start" >&2; exit 1; }
in_ns() { nsenter -t "$sd" -m -p -n -u -i "$@"; }
(in_ns /usr/bin/mavping respond udpin:127.0.0.1:14560 >/dev/null 2>&1 &)
for _ in $(seq 100); do
  [ "$(in_ns systemctl show -P ActiveState mavping-serve 2>/dev/null)" = active ] && break
  sleep 0.1
done
in_ns systemctl status mavping-serve --no-pager | sed -n '1,4p;/Main PID/p'
main=$(in_ns systemctl show -P MainPID mavping-serve)
# Its PID as this (outer) pid namespace sees it, for /proc.
outer=$(pgrep -P "$sd" -f "mavping serve")
echo "PID $main in the namespace, $outer outside:"
grep -E '^(Uid|Groups|CapEff|CapBnd|NoNewPrivs|Seccomp):' "/proc/$outer/status"

(in_ns python3 "$work/ptys.py" > "$work/ptys" &)
sleep 1
read -r service_pty respond_pty < "$work/ptys"
(in_ns /usr/bin/mavping respond "serial:$respond_pty:57600" >/dev/null 2>&1 &)
printf '[[link]]\nlink = "serial:%s:57600"\nname = "pty"\n' "$service_pty" >> "$work/serve.toml"
in_ns systemctl reload mavping-serve
sleep 10
scrape() { in_ns curl -s "http://127.0.0.1:9465$1" | grep -v '^#'; }
echo "--- /metrics after 10 s"
scrape /metrics | grep -E '^mavping_(link_up|requests_total|received_total|lost_total|exporter_config_reloads_total|exporter_config_last_reload_successful)'
echo "--- /probe?target=udpout:127.0.0.1:14560&count=5"
scrape '/probe?target=udpout:127.0.0.1:14560&count=5' |
  grep -E '^mavping_probe_(success|requests|received|lost)'
