# Run by tests/link/test_blender.sh inside a headless Blender (blender -b --python ... -- ARGS):
# the add-on tools/blender/facepuppet_live.py receives a take's --stream onto the ICT face
# imported from the same OBJ, records it as shape-key animation, and every recorded frame,
# evaluated by Blender at its scene frame, is compared with the take's PC2 (the frames
# `facepuppet play` makes) within --tol-mm. Then Record again after that Stop shows the live
# face (the live key back at 1, the first recording's keys muted: none adds to it), and six
# jittered stream frames on four scene frames are keyed as one key at 1 a scene frame, the
# latest stream frame on it (two would add: the deformation doubled). Prints "blender-live: ..." lines, the last one
# "blender-live: PASS" on success.
# ARGS: --addon PY --obj MESH.obj --pc2 TAKE.pc2 --port P [--tol-mm 0.1] [--timeout S]
import argparse
import importlib.util
import math
import socket
import struct
import sys
import time

import bpy
import numpy as np


def say(text):
    print("blender-live: " + text, flush=True)


def fail(text):
    say("FAIL: " + text)
    sys.exit(1)


argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
ap = argparse.ArgumentParser()
ap.add_argument("--addon", required=True)
ap.add_argument("--obj", required=True)
ap.add_argument("--pc2", required=True)
ap.add_argument("--port", type=int, required=True)
ap.add_argument("--tol-mm", type=float, default=0.1)
ap.add_argument("--timeout", type=float, default=120)
a = ap.parse_args(argv)

spec = importlib.util.spec_from_file_location("facepuppet_live", a.addon)
addon = importlib.util.module_from_spec(spec)
spec.loader.exec_module(addon)
addon.register()

bpy.ops.wm.obj_import(filepath=a.obj)
obj = bpy.context.selected_objects[0]
bpy.context.view_layer.objects.active = obj
bpy.context.scene.frame_start = 1
link = addon.FaceLink(obj, a.port, "TIMECODE")
link.start()  # (recording from the first frame on, as the Record button does)
say("listening on %d" % a.port)
t_end = time.time() + a.timeout
started = False
while time.time() < t_end:
    got = link.poll()
    if got and not started:
        started = True
    if started and not got:
        quiet_since = time.time()
        while time.time() - quiet_since < 3 and not link.poll():
            time.sleep(0.002)
        if time.time() - quiet_since >= 3:
            break
    time.sleep(0.001)
if not started:
    fail("nothing received")
rx = link.rx
recorded = link.stop()
say("received %d frames (%d packets, %d lost by sequence, %d incomplete, %d malformed); recorded %d "
    "shape keys; %s" % (rx.frames, rx.packets, rx.lost, rx.incomplete, rx.bad, recorded,
                        "timecode in %s" % bpy.context.scene.get("facepuppet_timecode_in", "-")))
if link.error:
    fail(link.error)

with open(a.pc2, "rb") as f:
    data = f.read()
sig, ver, n, start, rate, nframes = struct.unpack_from("<12siiffi", data, 0)
if recorded != nframes:
    fail("recorded %d frames, the take has %d" % (recorded, nframes))
mmu = rx.info["mm_per_unit"]
scene = bpy.context.scene
frames = [fr for fr, _ in link.recorded]
if frames != list(range(frames[0], frames[0] + len(frames))):
    fail("the recorded frames are not one a scene frame: %s..." % frames[:8])
say("keyed on scene frames %d..%d at %d fps (the stream's timecodes)" % (frames[0], frames[-1], scene.render.fps))
worst, worst_at = 0.0, None
co = np.zeros(3 * n, np.float32)
pc2 = np.frombuffer(data, "<f4", nframes * n * 3, 32).reshape(nframes, n, 3).astype(np.float64)
for k, fr in enumerate(frames):
    scene.frame_set(fr)
    dg = bpy.context.evaluated_depsgraph_get()
    me = obj.evaluated_get(dg).to_mesh()
    me.vertices.foreach_get("co", co)
    obj.evaluated_get(dg).to_mesh_clear()
    frame_worst = float(np.sqrt(((co.reshape(n, 3) - pc2[k]) ** 2).sum(1)).max()) * mmu
    if frame_worst > worst:
        worst, worst_at = frame_worst, k
moved = float(np.sqrt(((pc2[-1] - pc2[0]) ** 2).sum(1)).max()) * mmu  # (the last frame against the first)
say("largest difference from the take's frames: %.4f mm (frame %s; allowed %.3g mm); the face moved "
    "up to %.2f mm from the first frame to the last" % (worst, worst_at, a.tol_mm, moved))
if worst > a.tol_mm:
    fail("frame %d differs by %.4f mm" % (worst_at, worst))
if moved < 0.5:
    fail("the take hardly moves (%.3f mm): no test of the animation" % moved)


def evaluated(fr):
    """The face as Blender evaluates it at scene frame fr: n x 3 (mesh units)."""
    scene.frame_set(fr)
    dg = bpy.context.evaluated_depsgraph_get()
    me = obj.evaluated_get(dg).to_mesh()
    me.vertices.foreach_get("co", co)
    obj.evaluated_get(dg).to_mesh_clear()
    return co.reshape(n, 3).astype(np.float64)


def feed(frame, t, q):
    """One stream frame handed to the link as the receiver would: offsets q (steps, n x 3)."""
    rx.q[:] = q.reshape(-1)
    link._frame({"frame": frame, "time": t, "timecode": "", "parts": 1, "got": 1, "channels": [],
                 "complete": True})
    return rx.positions(link.neutral).reshape(n, 3).astype(np.float64)


def off_mm(got, want):
    return float(np.sqrt(((got - want) ** 2).sum(1)).max()) * mmu


# Record again after Stop: the viewport shows the live face (the live key back at 1), and the
# first recording's keys do not add to it on the scene frames they hold.
rng = np.random.default_rng(55)
q_live = rng.integers(-40, 40, (n, 3)).astype(np.int32)
link.start()
live = feed(100000, 0.0, q_live)
mid = frames[len(frames) // 2]
d = off_mm(evaluated(mid), live)
say("recording again: scene frame %d shows the live face within %.4f mm (live key %.1f)"
    % (mid, d, link.live.value))
if d > 0.05:
    fail("after Record, Stop, Record the viewport is %.3f mm off the live face (live key at %.1f)"
         % (d, link.live.value))

# Two stream frames on one scene frame (live frame times jitter): one key at 1 there, the later
# frame's; relative keys add, so two at 1 would double the deformation.
fps = scene.render.fps
times = [0.0, 0.3 / fps, 1.0 / fps, 2.0 / fps, 2.4 / fps, 3.0 / fps]   # (scene frames +0 +0 +1 +2 +2 +3)
link.start()
shown = [feed(200000 + k, t, (k + 1) * q_live // 3) for k, t in enumerate(times)]
keys_before = len(obj.data.shape_keys.key_blocks)
got = link.stop()
sf = sorted(fr for fr, _ in link.recorded)
for fr, k in zip(range(sf[0], sf[0] + 4), (1, 2, 4, 5)):   # (the latest stream frame on each)
    d = off_mm(evaluated(fr), shown[k])
    if d > 0.05:
        fail("scene frame %d is %.3f mm off stream frame %d, the latest on it (two keys at 1?)"
             % (fr, d, 200000 + k))
if got != 4 or sf != list(range(sf[0], sf[0] + 4)):
    fail("6 stream frames on 4 scene frames recorded %d keys on scene frames %s" % (got, sf))
say("6 jittered stream frames on 4 scene frames: 4 keys, each scene frame the latest frame on it "
    "(%d shape keys on the face)" % keys_before)
# A slow receiver (docs/osc.md, "A receiver's buffer"): the add-on asks for a receive buffer of
# two keyframes of the face at their largest (9 bytes a vertex; 4 MiB at least) and says so when
# the system grants less. A keyframe of every vertex of this face (ceil(n / 159) packets of 1,400
# bytes, one burst) sent while nothing reads is held whole.
say("receive buffer: %d KiB granted of %d KiB asked%s" % (rx.rcvbuf >> 10, rx.rcvbuf_asked >> 10,
                                                         "; " + rx.warning if rx.warning else ""))
if rx.rcvbuf_asked < max(4 << 20, 18 * n):
    fail("the add-on asks for a %d-byte receive buffer, less than two keyframes of %d vertices"
         % (rx.rcvbuf_asked, n))
try:
    rmem_max = int(open("/proc/sys/net/core/rmem_max").read())
except OSError:
    rmem_max = None
if rmem_max is not None:
    big = addon.StreamReceiver(0, rcvbuf=rmem_max + (1 << 20))
    if not big.warning or "%d KiB" % (big.rcvbuf >> 10) not in big.warning:
        fail("asking %d bytes beyond net.core.rmem_max = %d was not reported (%r)"
             % (rmem_max + (1 << 20), rmem_max, big.warning))
    say("asking beyond net.core.rmem_max (%d) is reported: %s" % (rmem_max, big.warning))
    big.close()
slow = addon.StreamReceiver(0, rcvbuf=link.rx.rcvbuf_asked)
burst = -(-n // 159)
out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
for _ in range(burst):
    out.sendto(b"\0" * 1400, slow.sock.getsockname())
time.sleep(0.2)
held = slow.poll()
slow.close()
out.close()
say("a keyframe's burst of %d packets sent while nothing read: %d held" % (burst, held))
if held != burst and not slow.warning:
    fail("a slow receiver held %d of a keyframe's %d packets with the buffer it asked granted"
         % (held, burst))
say("PASS")
