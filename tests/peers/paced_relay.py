#!/usr/bin/env python3
"""A radio link made of two pseudo-terminals: unlike a bare pty pair (which
passes bytes as fast as they come), it carries them at a baud rate, 10 bits
a byte, over one channel that both directions share (half duplex, as a SiK
radio's air time is), delivers what it read after a fixed latency, and
drops the bytes that do not fit in its transmit buffer, as a radio does
(a frame cut in two is lost whole: its CRC fails). So a link's capacity
is known: baud / 10 bytes per second, both directions together.

Prints "ready", then one line "A_PATH B_PATH" (the two device paths), and
carries bytes between them. Prints one JSON line of ground truth on SIGTERM:
bytes carried and dropped each way.
"""
import argparse
import collections
import json
import os
import sys
import time

import ptys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--baud", type=int, default=57600, help="bits per second, 10 per byte")
    ap.add_argument("--buffer", type=int, default=1024,
                    help="bytes waiting for the channel beyond which a read is dropped")
    ap.add_argument("--latency-ms", type=float, default=20.0,
                    help="delay of every read after its last byte is through the channel")
    args = ap.parse_args()

    (ma, pa), (mb, pb) = ptys.open_raw_pair()
    other = {ma: mb, mb: ma}
    name = {ma: "a_to_b", mb: "b_to_a"}

    until = ptys.UntilSignalled()
    print("ready", flush=True)
    print(pa, pb, flush=True)

    seconds_per_byte = 10.0 / args.baud
    latency = args.latency_ms / 1000.0
    channel_free = 0.0
    # Reads on their way: (when delivered, where, bytes), in channel order.
    in_flight = collections.deque()
    # Reads not yet through the channel: (when through, length).
    held = collections.deque()
    truth = {"a_to_b": 0, "b_to_a": 0, "dropped_a_to_b": 0, "dropped_b_to_a": 0}
    while until.running:
        now = time.monotonic()
        while in_flight and in_flight[0][0] <= now:
            _, fd, data = in_flight.popleft()
            try:
                os.write(fd, data)
            except OSError:
                pass  # nobody has that end open yet: the bytes are lost
        timeout = 0.05
        if in_flight:
            timeout = max(0.0, min(timeout, in_flight[0][0] - now))
        ready = ptys.read_ready([ma, mb], timeout)
        now = time.monotonic()
        while held and held[0][0] <= now:
            held.popleft()
        for fd, data in ready:
            room = max(0, args.buffer - sum(length for _, length in held))
            if len(data) > room:
                truth["dropped_" + name[fd]] += len(data) - room
                data = data[:room]
            if not data:
                continue
            start = max(now, channel_free)
            channel_free = start + len(data) * seconds_per_byte
            held.append((channel_free, len(data)))
            in_flight.append((channel_free + latency, other[fd], data))
            truth[name[fd]] += len(data)
    print(json.dumps(truth), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
