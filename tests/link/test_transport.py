#!/usr/bin/env python3
"""`facepuppet play TAKE --control osc:PORT`: the transport over OSC (tests/link/test_control.sh
runs it on the take the control test recorded). Cued at the first frame ("stopped", time 0);
/fp/play: "playing", the time advancing at the take's pace; /fp/stop: "stopped", the time held;
/fp/seek 0.5: the time at the first frame at or after 0.5 s; /fp/play to the end: "ended";
/fp/record/start answered with an error (play has no takes); /fp/quit ends it (exit 0).
The status names the played take (its slate and number, from `facepuppet info`), and its frame
and timecode are the take's at the playhead: frame 0 and the take's first timecode when cued;
after the seek the frame whose time the status gives (frames at the take's rate) and the
timecode that many frames on.
Usage: test_transport.py FACEPUPPET_BIN PLUGIN_DIR TAKE WORK_DIR. Prints "PASS" last."""
import os
import random
import select
import socket
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fposc  # noqa: E402

fp, plugdir, take, work = sys.argv[1:5]

info = subprocess.run([fp, "info", take], capture_output=True, text=True).stdout
fields = dict((line.split(None, 1) + [""])[:2] for line in info.splitlines()[1:] if line.strip())
take_slate, take_number = fields["slate"].strip(), int(fields["take"])
rate_n, rate_d = (int(x) for x in fields["frame"].split()[1].split("/"))  # "rate 60/1 (...)"
first_tc = fields["timecode"].split()[0]
fps = rate_n / rate_d


def tc_frames(tc):
    h, m, sec, f = (int(x) for x in tc.replace(";", ":").split(":"))
    return ((h * 60 + m) * 60 + sec) * round(fps) + f


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


for attempt in range(5):
    port = random.randint(20000, 60000)
    err = open(os.path.join(work, "play.err"), "w")
    p = subprocess.Popen([fp, "play", "--plugin-dir", plugdir, take, "--control", "osc:%d" % port],
                         stdout=subprocess.DEVNULL, stderr=err)
    for _ in range(600):
        text = open(os.path.join(work, "play.err")).read()
        if "listening on port" in text or p.poll() is not None:
            break
        time.sleep(0.1)
    if "listening on port" in text:
        break
    p.wait()
    if "cannot listen" not in text:
        fail("play did not listen: " + text)
else:
    fail("no free port")

sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.bind(("127.0.0.1", 0))


def command(address, *args, expect="ok"):
    sock.sendto(fposc.encode(address, *args), ("127.0.0.1", port))
    # 10 s, times FP_TEST_TIME_SCALE (the sanitizers: play opens the take and the face after
    # it starts listening, several times slower there)
    if not select.select([sock], [], [], 10 * max(1, int(os.environ.get("FP_TEST_TIME_SCALE", "1"))))[0]:
        fail("%s: no reply" % address)
    a, r = fposc.decode(sock.recv(65536))
    st = dict(zip(["command", "result", "state", "timecode", "slate", "take", "recording", "time",
                   "frame", "refused"], r))
    if a != "/fp/status" or st["command"] != address or not st["result"].startswith(expect):
        fail("%s answered %r" % (address, st))
    print("  %-18s %-6s -> %s %s time %.3f frame %d" % (address, " ".join(map(str, args)), st["result"],
                                                     st["state"], st["time"], st["frame"]))
    return st


try:
    st = command("/fp/status")
    if st["state"] != "stopped" or st["time"] != 0:
        fail("not cued at the first frame: %r" % st)
    if (st["slate"], st["take"]) != (take_slate, take_number):
        fail("the status does not name the played take %s %d: %r" % (take_slate, take_number, st))
    if st["frame"] != 0 or st["timecode"] != first_tc:
        fail("cued: frame 0 at %s expected: %r" % (first_tc, st))
    command("/fp/play")
    time.sleep(0.4)
    a = command("/fp/status")
    if a["state"] != "playing" or not 0.2 < a["time"] < 1.5:
        fail("playing 0.4 s: %r" % a)
    b = command("/fp/stop")
    time.sleep(0.3)
    c = command("/fp/status")
    if c["state"] != "stopped" or c["time"] != b["time"]:
        fail("the time moved while stopped: %r -> %r" % (b, c))
    d = command("/fp/seek", 0.5)
    if not 0.5 - 1e-6 <= d["time"] < 0.5 + 0.05 or d["state"] != "stopped":
        fail("seek 0.5: %r" % d)
    if abs(d["frame"] - d["time"] * fps) > 0.51:
        fail("seek 0.5: frame %d is not the take's at %.3f s (%g fps)" % (d["frame"], d["time"], fps))
    if tc_frames(d["timecode"]) - tc_frames(first_tc) != d["frame"]:
        fail("seek 0.5: timecode %s is not %d frames after %s" % (d["timecode"], d["frame"], first_tc))
    command("/fp/record/start", expect="error: no take folder")
    command("/fp/play")
    for _ in range(100):
        time.sleep(0.1)
        e = command("/fp/status")
        if e["state"] == "ended":
            break
    else:
        fail("the take did not end")
    command("/fp/quit")
    if p.wait(30) != 0:
        fail("play exited %d" % p.returncode)
    print("PASS")
finally:
    if p.poll() is None:
        p.kill()
