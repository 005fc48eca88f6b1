#!/usr/bin/env python3
"""Receive a `forward=osc:...` stream on loopback and report each event's latency: its arrival
(CLOCK_MONOTONIC, the host clock facepuppet stamps events with) minus its bundle's timetag (the
event's time: fp_forward.h adds 1 s so that it is never "immediate"). On one machine both clocks
are the same, so this is the time from the event's measurement (the replay pushes it then) to its
arrival in another process. Usage: forward_latency.py PORT; prints "listening", then at the end
(3 s without packets) "events N, latency median M us, p99 P us, max X us"."""
import os
import select
import socket
import struct
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fposc  # noqa: E402

sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.bind(("127.0.0.1", int(sys.argv[1])))
print("listening", flush=True)
lat, addresses = [], {}
while select.select([sock], [], [], 3.0 if lat else 60.0)[0]:
    data = sock.recv(65536)
    now = time.monotonic_ns()
    if data[:8] != b"#bundle\0":
        sys.exit("FAIL: not a bundle")
    sec, frac = struct.unpack_from(">II", data, 8)
    at, elements = 16, []
    while at < len(data):  # the sender's origin (/facepuppet/origin), then the event
        (size,) = struct.unpack_from(">i", data, at)
        elements.append(fposc.decode(data[at + 4:at + 4 + size])[0])
        at += 4 + size
    if elements[:1] != ["/facepuppet/origin"] or len(elements) != 2:
        sys.exit("FAIL: a bundle of %s (expected /facepuppet/origin and one event)" % elements)
    addresses[elements[1]] = addresses.get(elements[1], 0) + 1
    lat.append((now - ((sec - 1) * 1000000000 + (frac * 1000000000 >> 32))) / 1000.0)
lat.sort()
if not lat:
    sys.exit("FAIL: nothing received")
print("events %d (%s), latency median %.0f us, p99 %.0f us, max %.0f us" % (
    len(lat), ", ".join("%s %d" % kv for kv in sorted(addresses.items())), lat[len(lat) // 2],
    lat[min(len(lat) - 1, int(0.99 * len(lat)))], lat[-1]))
