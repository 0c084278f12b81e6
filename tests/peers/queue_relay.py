#!/usr/bin/env python3
"""A UDP relay between a ground station and one vehicle with a queue in one
direction or both: the delay it adds to a datagram grows linearly from 0
to PEAK seconds over RISE seconds, starting START seconds after the first
datagram from the vehicle, then drains as fast, as a relay or modem
buffer does (PEAK < RISE, so datagrams stay in order). Nothing is lost.

  --vehicle HOST:PORT      where the vehicle listens
  --queue-down PEAK@RISE   the queue towards the ground (replies, telemetry)
  --queue-up PEAK@RISE     the queue towards the vehicle (requests)
  --start SECONDS          when the queues start to grow (default 3)

Prints "ready", then the port it listens on for the ground station. On
SIGTERM prints one JSON line of ground truth: per direction, datagrams
carried and the delay it gave them (max, and p50/p99), in ms.
"""
import argparse
import heapq
import json
import select
import signal
import socket
import time


def ramp(spec):
    if not spec:
        return None
    peak, rise = (float(x) for x in spec.split("@"))
    assert 0 < peak < rise, "PEAK must be under RISE"
    return peak, rise


def delay_at(queue, since):
    """The delay the queue gives a datagram entering it `since` seconds
    after the queues started."""
    if queue is None or since <= 0:
        return 0.0
    peak, rise = queue
    share = since / rise if since <= rise else max(0.0, 2.0 - since / rise)
    return peak * share


def percentile(values, p):
    if not values:
        return None
    values = sorted(values)
    return values[min(len(values) - 1, int(p * len(values)))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vehicle", required=True)
    ap.add_argument("--queue-down", default="")
    ap.add_argument("--queue-up", default="")
    ap.add_argument("--start", type=float, default=3.0)
    args = ap.parse_args()
    host, port = args.vehicle.rsplit(":", 1)
    vehicle = (host, int(port))
    queues = {"down": ramp(args.queue_down), "up": ramp(args.queue_up)}

    ground_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ground_sock.bind(("127.0.0.1", 0))
    vehicle_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    vehicle_sock.bind(("127.0.0.1", 0))
    ground = None
    began = None
    held = []  # (due, order, direction, data)
    order = 0
    delays = {"down": [], "up": []}

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(True))
    print("ready", flush=True)
    print(ground_sock.getsockname()[1], flush=True)
    while not stop:
        now = time.monotonic()
        while held and held[0][0] <= now:
            _, _, direction, data = heapq.heappop(held)
            if direction == "up":
                vehicle_sock.sendto(data, vehicle)
            elif ground is not None:
                ground_sock.sendto(data, ground)
        wait = max(0.0, held[0][0] - now) if held else 0.05
        try:
            ready, _, _ = select.select([ground_sock, vehicle_sock], [], [], min(wait, 0.05))
        except InterruptedError:
            continue
        for sock in ready:
            data, source = sock.recvfrom(65536)
            now = time.monotonic()
            if sock is ground_sock:
                ground, direction = source, "up"
            else:
                direction = "down"
                if began is None:
                    began = now + args.start
            delay = delay_at(queues[direction], now - began if began is not None else 0.0)
            delays[direction].append(delay)
            order += 1
            heapq.heappush(held, (now + delay, order, direction, data))
    truth = {}
    for direction, values in delays.items():
        truth[direction] = {
            "datagrams": len(values),
            "max_ms": max(values, default=0.0) * 1e3,
            "p50_ms": (percentile(values, 0.5) or 0.0) * 1e3,
            "p99_ms": (percentile(values, 0.99) or 0.0) * 1e3,
        }
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    main()
