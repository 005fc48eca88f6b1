#!/usr/bin/env python3
"""live --control and --stream across a mesh dropped on the window (run under xvfb-run by
ctest; docs/osc.md "On stage"): a client subscribes to the status, a receiver takes the stream,
and the script drops another face (Lee Perry-Smith's, 8,838 vertices) on the ICT face's
window 3 s in. After the drop:
  - the subscriber still gets the status pushed (once a second): the control surface keeps
    its socket, port and subscribers (before: it was closed and opened again, the subscribers
    forgotten, no push after the drop; with osc:0 another port);
  - the stream's /fp/stream/info names the new face: its vertex count, the crc32 of its
    positions and its path (before: the new count and crc with the first face's path), and
    starts at seq 0 (a new stream, docs/osc.md).
Usage: test_live_drop.py FACEPUPPET_BIN PLUGIN_DIR FACE OTHER_FACE WORK_DIR
Prints "PASS" last on success; exit 1 with "FAIL: ..." otherwise."""
import os
import re
import select
import socket
import struct
import subprocess
import sys
import time
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fposc  # noqa: E402

fp, plugdir, face, other, work = (os.path.abspath(a) for a in sys.argv[1:6])


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def crc_of(path):
    data = bytearray()
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                data += struct.pack("<3f", *(float(x) for x in line.split()[1:4]))
    return zlib.crc32(bytes(data)), len(data) // 12


stream = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
stream.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
stream.bind(("127.0.0.1", 0))
ctl = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
ctl.bind(("127.0.0.1", 0))
err_path = os.path.join(work, "live-drop.err")
p = subprocess.Popen([fp, "live", "-q", "--plugin-dir", plugdir, "--mesh", face, "--size", "320x240",
                      "--control", "osc:0", "--stream", "osc:127.0.0.1:%d" % stream.getsockname()[1],
                      "--script", "wait seconds 3; drop %s; wait seconds 4; close" % other],
                     stdout=subprocess.DEVNULL, stderr=open(err_path, "w"), cwd=work)
port = fposc.control_port(p, err_path)
if port is None:
    p.kill()
    fail("live did not listen: %s" % open(err_path).read())
ctl.sendto(fposc.encode("/fp/subscribe"), ("127.0.0.1", port))
infos, pushes = [], []          # (arrival, seq, vertices, crc, path); arrival times of pushes
while p.poll() is None or select.select([stream, ctl], [], [], 0)[0]:
    for s in select.select([stream, ctl], [], [], 0.2)[0]:
        data = s.recv(65536)
        try:
            address, args = fposc.decode(data)
        except ValueError:
            continue
        if address == "/fp/stream/info":
            infos.append((time.time(), args[0], args[1], args[6] & 0xffffffff, args[7]))
        elif address == "/fp/status" and args[0] == "push":
            pushes.append(time.time())
rc = p.wait()
if rc != 0:
    fail("live exited %d: %s" % (rc, open(err_path).read()))
log = open(err_path).read()
new_crc, new_n = crc_of(other)
first = [i for i in infos if i[2] != new_n]
second = [i for i in infos if i[2] == new_n]
print("  stream: %d infos of the first face, %d of the dropped one (seq %s, %d vertices, crc %08x, %s)"
      % (len(first), len(second), second[0][1] if second else "-", new_n,
         second[0][3] if second else 0, second[0][4] if second else "-"))
if not first or not second:
    fail("the stream did not go on across the drop: %s" % log)
if second[0][1] != 0 or second[0][3] != new_crc or not second[0][4].endswith(os.path.basename(other)):
    fail("the stream's info after the drop: seq %d crc %08x path %s, wanted seq 0 crc %08x %s"
         % (second[0][1], second[0][3], second[0][4], new_crc, other))
after = [t for t in pushes if t > second[0][0] + 0.5]
print("  status pushes: %d in all, %d more than 0.5 s after the drop; ports said: %s"
      % (len(pushes), len(after), re.findall(r"listening on port (\d+)", log)))
if len(after) < 2:
    fail("the subscriber got %d pushes after the drop (its subscription lost)" % len(after))
if len(re.findall(r"--control: listening on port", log)) != 1:
    fail("the control surface was opened again: %s" % log)
print("PASS")
