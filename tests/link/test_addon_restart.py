#!/usr/bin/env python3
"""The Blender add-on's receiver (tools/blender/facepuppet_live.py, StreamReceiver: no bpy
needed) across a sender that starts again, as on a stage where facepuppet is restarted while
Blender stays connected (docs/osc.md, Stream): two `run --stream` one after the other to the
same port, the receiver polling throughout.
  - packets lost by sequence: 0 (loopback, read as they come). Before: the second run's seq 0
    after the first run's last counted as 2^32 - 1 - last lost packets (the panel said
    "4294966292 packets lost");
  - one restart counted;
  - the face the receiver holds at the end is the second run's last frame: within the
    stream's precision (step x sqrt(3)/2) of the run's --out, vertex for vertex.
Usage: test_addon_restart.py FACEPUPPET_BIN PLUGIN_DIR MESH RECORDING WORK_DIR
Prints "PASS" last on success; exit 1 with "FAIL: ..." otherwise."""
import atexit
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "..", "tools", "blender"))
import facepuppet_live as addon  # noqa: E402

fp, plugdir, mesh, rec, work = sys.argv[1:6]
work = tempfile.mkdtemp(prefix="fp-addon-restart-", dir=work)
atexit.register(shutil.rmtree, work, True)


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def read_obj(path):
    out = []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                out.extend(float(x) for x in line.split()[1:4])
    return out


rx = None
for _ in range(5):
    port = random.randint(20000, 60000)
    try:
        rx = addon.StreamReceiver(port)
        break
    except OSError:
        continue
if rx is None:
    fail("no free port in 5 tries")
for k in range(2):
    out = os.path.join(work, "run%d.obj" % k)
    p = subprocess.Popen([fp, "run", "--plugin-dir", plugdir, "--mesh", mesh, "--input",
                          "replay:%s" % rec, "--duration", "1.5" if k == 0 else "1", "-q",
                          "--out", out, "--stream", "osc:127.0.0.1:%d" % port],
                         stdout=subprocess.DEVNULL, stderr=open(os.path.join(work, "run%d.err" % k), "w"))
    while p.poll() is None:
        rx.poll()
        time.sleep(0.002)
    if p.returncode != 0:
        fail("run %d: exit %d: %s" % (k, p.returncode, open(os.path.join(work, "run%d.err" % k)).read()))
    for _ in range(50):
        rx.poll()
        time.sleep(0.01)
    print("  after run %d: %d frames, %d packets, %d lost by sequence, %d restarts, %d incomplete"
          % (k, rx.frames, rx.packets, rx.lost, getattr(rx, "restarts", 0), rx.incomplete))
rx.close()
if rx.lost != 0:
    fail("%d packets counted lost on loopback (a sender's restart taken for a gap)" % rx.lost)
if getattr(rx, "restarts", 0) != 1:
    fail("%d restarts counted, wanted 1" % getattr(rx, "restarts", 0))
neutral = read_obj(mesh)
got = rx.positions(neutral)
want = read_obj(os.path.join(work, "run1.obj"))
if len(want) != len(got):
    fail("%d coordinates received, the run wrote %d" % (len(got), len(want)))
mm = rx.info["mm_per_unit"]
worst = max(math.sqrt(sum((got[i + a] - want[i + a]) ** 2 for a in range(3)))
            for i in range(0, len(got), 3)) * mm
tol = rx.info["step"] * math.sqrt(3) / 2 + 1e-3
moved = sum(1 for i in range(0, len(want), 3)
            if any(abs(want[i + a] - neutral[i + a]) * mm > 0.1 for a in range(3)))
print("  the second run's last frame: %d vertices moved; received within %.4f mm (allowed %.4f)"
      % (moved, worst, tol))
if moved == 0:
    fail("the run moved no vertex: nothing was checked")
if worst > tol:
    fail("the face held is %.4f mm from the second run's last frame" % worst)
print("PASS")
