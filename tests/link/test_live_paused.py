#!/usr/bin/env python3
"""live --control while the performer has paused the window (space; run under xvfb-run by
ctest; docs/osc.md "Control": each command is answered): the script pauses at 1.5 s and goes
on at 7.5 s; a client sends /fp/status and /fp/slate while paused and wants each answered
within 2 s, "ok", the slate set at once. Before: the viewer bracketed only the session's
steps with the control surface, so nothing was answered or pushed while paused and the
commands queued until the performer went on.
Usage: test_live_paused.py FACEPUPPET_BIN PLUGIN_DIR FACE WORK_DIR
Prints "PASS" last on success; exit 1 with "FAIL: ..." otherwise."""
import os
import select
import socket
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fposc  # noqa: E402

fp, plugdir, face, work = (os.path.abspath(a) for a in sys.argv[1:5])


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


err_path = os.path.join(work, "live-paused.err")
p = subprocess.Popen([fp, "live", "-q", "--plugin-dir", plugdir, "--mesh", face, "--size", "320x240",
                      "--control", "osc:0", "--script",
                      "wait seconds 1.5; key space; print hud; wait seconds 6; key space; wait frames 2; close"],
                     stdout=subprocess.PIPE, stderr=open(err_path, "w"), cwd=work, text=True)
port = fposc.control_port(p, err_path)
if port is None:
    p.kill()
    fail("live did not listen: %s" % open(err_path).read())
line = p.stdout.readline()  # "hud ... badge PAUSED ...": the window is paused now
if "badge PAUSED" not in line:
    p.kill()
    fail("the script's pause did not show: %r" % line)
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(("127.0.0.1", 0))
time.sleep(0.5)
for args, want_slate in [(("/fp/status",), None), (("/fp/slate", "paused_2"), "paused_2")]:
    t0 = time.time()
    s.sendto(fposc.encode(*args), ("127.0.0.1", port))
    if not select.select([s], [], [], 2)[0]:
        p.kill()
        fail("%s while paused: no reply in 2 s" % args[0])
    address, reply = fposc.decode(s.recv(65536))
    print("  paused: %-12s -> %s %s, slate %s, after %.0f ms" % (args[0], address, reply[1], reply[4],
                                                                 (time.time() - t0) * 1000))
    if reply[0] != args[0] or reply[1] != "ok" or (want_slate and reply[4] != want_slate):
        p.kill()
        fail("%s while paused answered %r" % (args[0], reply))
rc = p.wait(60)
if rc != 0:
    fail("live exited %d: %s" % (rc, open(err_path).read()))
print("PASS")
