#!/usr/bin/env python3
"""The Blender add-on's listen address (tools/blender/facepuppet_live.py, listen_udp and
StreamReceiver: no bpy needed) takes what facepuppet's bind= takes (docs/osc.md): a stream
sent to [::1] (facepuppet --stream osc:[::1]:PORT, or a sender whose localhost is ::1) must
reach a receiver on 127.0.0.1/localhost (the IPv4 loopback and [::1] beside it), on ::1 or
[::1] (that alone), and on 0.0.0.0 or :: (one [::] socket, IPv4 and IPv6). Before: the
receiver made an IPv4 socket whatever the address, so ::1 and :: raised, and a stream to [::1]
was never heard on 127.0.0.1 or 0.0.0.0. A name other than localhost is refused (ValueError).
Packets are /fp/stream/info messages as facepuppet sends them, on loopback.
Usage: test_addon_listen.py
Prints "PASS" last on success; exit 1 with "FAIL: ..." otherwise. Where the machine has no
IPv6 loopback the IPv6 cases cannot be run: it says so and exits 77 (skipped)."""
import os
import socket
import sys
import time

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "..", "tools", "blender"))
sys.path.insert(0, here)
import facepuppet_live as addon  # noqa: E402
import fposc  # noqa: E402


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


try:
    probe = socket.socket(socket.AF_INET6, socket.SOCK_DGRAM)
    probe.bind(("::1", 0))
    probe.close()
except OSError as e:
    print("SKIP: no IPv6 loopback here (%s)" % e)
    sys.exit(77)


def heard(rx, dest, family, n):
    """Send one /fp/stream/info naming n vertices to dest; True once rx has it (2 s at most)."""
    info = fposc.encode("/fp/stream/info", 0, n, 1.0, 0.001, 60, 60.0, 0, "face-%d.obj" % n)
    with socket.socket(family, socket.SOCK_DGRAM) as out:
        out.sendto(info, dest)
    t_end = time.time() + 2.0
    while time.time() < t_end:
        rx.poll()
        if rx.info is not None and rx.info["n"] == n:
            return True
        time.sleep(0.01)
    return False


V4, V6 = socket.AF_INET, socket.AF_INET6
# address listened on -> the loopbacks that must reach it
cases = [("127.0.0.1", [V4, V6]), ("localhost", [V4, V6]), ("::1", [V6]), ("[::1]", [V6]),
         ("0.0.0.0", [V4, V6]), ("::", [V4, V6]), ("[::]", [V4, V6])]
n = 100
for host, families in cases:
    try:
        rx = addon.StreamReceiver(0, host)
    except (OSError, ValueError) as e:
        fail("address %s: the receiver could not listen: %s" % (host, e))
    port = rx.sock.getsockname()[1]
    if rx.warning and "receive buffer" not in rx.warning:
        fail("address %s: warned %r" % (host, rx.warning))
    for fam in families:
        n += 1
        dest = ("127.0.0.1", port) if fam == V4 else ("::1", port)
        if not heard(rx, dest, fam, n):
            fail("address %s (listening on %s): a packet to %s:%d was not received"
                 % (host, getattr(rx, "listening", "?"), "[::1]" if fam == V6 else "127.0.0.1", port))
    print("  %-10s listening on %s: heard from %s" % (host, rx.listening,
          " and ".join("127.0.0.1" if f == V4 else "[::1]" for f in families)))
    rx.close()

# an IPv6-only address is not heard on IPv4 (it is that address alone, as bind=::1)
rx = addon.StreamReceiver(0, "::1")
if heard(rx, ("127.0.0.1", rx.sock.getsockname()[1]), V4, 7):
    fail("address ::1 received a packet sent to 127.0.0.1")
rx.close()

for bad in ("example.invalid", "not an address", "1.2.3"):
    try:
        addon.StreamReceiver(0, bad).close()
        fail("address %r was accepted" % bad)
    except ValueError as e:
        if "expected an IP address" not in str(e):
            fail("address %r: the error does not say what is expected: %s" % (bad, e))
print("PASS")
