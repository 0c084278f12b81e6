#!/usr/bin/env bash
# The cost of --tlog on the hot path: CPU per PING of a 1 kHz run against
# `mavping respond` over loopback UDP, with and without --tlog, alternated
# so the machine's load falls on both alike. CPU from wait4(2) (user +
# system, to the microsecond). Usage:
#   bash scripts/bench-record.sh            # 3 rounds of 10,000 PINGs each way
#   ROUNDS=5 COUNT=20000 bash scripts/bench-record.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
exec python3 - "${ROUNDS:-3}" "${COUNT:-10000}" <<'PY'
import json, os, socket, subprocess, sys, tempfile

rounds, count = int(sys.argv[1]), int(sys.argv[2])
bin = "target/release/mavping"
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0))
port = s.getsockname()[1]; s.close()
respond = subprocess.Popen([bin, "respond", f"udpin:127.0.0.1:{port}"],
                           stdout=subprocess.PIPE, text=True)
respond.stdout.readline()
tlog = os.path.join(tempfile.mkdtemp(), "bench.tlog")

def run(record):
    args = [bin, "--rate", "1000", "-c", str(count), "-W", "1s", "--json", "-q"]
    if record:
        args += ["--tlog", tlog]
    p = subprocess.Popen(args + [f"udpout:127.0.0.1:{port}"], stdout=subprocess.PIPE, text=True)
    out = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    summary = [json.loads(l) for l in out.splitlines() if '"type":"summary"' in l][-1]
    r = summary["responders"][0]
    cpu = ru.ru_utime + ru.ru_stime
    return cpu / summary["requests"] * 1e6, r["received"], summary["requests"], ru.ru_maxrss

rows = {False: [], True: []}
for i in range(rounds):
    for record in (False, True):
        us, received, sent, rss = run(record)
        rows[record].append(us)
        size = os.path.getsize(tlog) if record else 0
        print(f"round {i + 1} {'--tlog' if record else 'plain '}: {us:.2f} µs CPU per PING, "
              f"{received}/{sent} received, peak RSS {rss / 1024:.1f} MB"
              + (f", log {size} bytes" if record else ""), flush=True)
respond.terminate(); respond.wait()
plain, rec = sorted(rows[False]), sorted(rows[True])
mid = lambda v: v[len(v) // 2]
print(f"median CPU per PING at 1 kHz: plain {mid(plain):.2f} µs, --tlog {mid(rec):.2f} µs "
      f"({mid(rec) - mid(plain):+.2f} µs, {100 * (mid(rec) / mid(plain) - 1):+.1f} %)")
PY
