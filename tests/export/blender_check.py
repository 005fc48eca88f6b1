# Blender's side of tests/export/test_export_blender.sh (issue 53): run headless by
#   blender -b --factory-startup --python-exit-code 1 --python blender_check.py -- \
#       --readme README.md --glb T.glb --obj FACE.obj --pc2 T.pc2 --mdd T.mdd \
#       --fps 60 --frames 160 --scale 0.01 --height 0.338 [--tol 0.03] \
#       [--face F.glb --face-pc2 T2.pc2 --face-glb T2.glb --face-fps 30000/1001 \
#        --face-frames N --face-scale 0.01]
# 1. glb: bpy.ops.import_scene.gltf; the face's world-space bounding box is --height metres
#    tall (Blender's Z, within --tol); the JSON names the rate (asset.extras.frameRate); the
#    shape-key keys span the take's duration at the scene's rate; at the take's moving frames
#    Blender's evaluated face is the take's (the PC2) within --max-error-mm (default 0.1).
# 2. pc2: the README's recipe (the fenced block after "<!-- blender-recipe"), executed as
#    written with the figures given here; the scene runs at --fps, and scene frame
#    start + k shows the take's frame k exactly (the cache's frame k, which fp-export-check
#    found bit-identical to the take), at frames where the face moves from one frame to the
#    next (so a cache played slow or one frame off would not pass).
# 3. mdd: the same recipe, then the README's Time Mode block in a 24 fps scene: scene frame
#    start + f shows the take's frame at f / 24 s.
# 4. with --face (a take on a glTF face): the README's glTF-face recipe plays --face-pc2 on the
#    face imported from its GLB (scene frame start + k the take's frame k, in Blender's world);
#    and --face-glb in a 29.97 fps scene, its keys moved by the README's block, within 0.1 mm.
# Prints "blender-check: ..." lines; any failed check raises (exit 1 by --python-exit-code).
import json
import os
import re
import struct
import sys
from fractions import Fraction

import numpy

if "bool" not in numpy.__dict__:
    # Debian 12: Blender 3.4's glTF importer uses numpy.bool, gone in Debian's numpy 1.24
    # (KhronosGroup/glTF-Blender-IO issue 1844, fixed in Blender 3.5)
    numpy.bool = bool

import bpy  # noqa: E402  (after the numpy shim)


def say(msg):
    print("blender-check: " + msg, flush=True)


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    a = {"tol": "0.03"}
    for i in range(0, len(argv) - 1, 2):
        a[argv[i].lstrip("-")] = argv[i + 1]
    for k in ("readme", "glb", "obj", "pc2", "mdd", "fps", "frames", "scale", "height"):
        if k not in a:
            raise SystemExit("blender_check.py: --%s missing" % k)
    return a


def recipe_blocks(readme):
    """The README's recipe: {marker name: python source} for each fenced block after a
    "<!-- blender-recipe..." comment."""
    text = open(readme, encoding="utf-8").read()
    blocks = {}
    for m in re.finditer(r"<!-- (blender-recipe[\w-]*)[^>]*-->\s*```python\n(.*?)```", text, re.S):
        blocks[m.group(1)] = m.group(2)
    if any(k not in blocks for k in ("blender-recipe", "blender-recipe-mdd-time",
                                     "blender-recipe-gltf-face", "blender-recipe-gltf-rate")):
        raise AssertionError("README: no blender-recipe blocks (found %s)" % sorted(blocks))
    return blocks


def run_block(src, env):
    """Execute a README block in env, without its line of placeholder figures ('# yours')."""
    code = "\n".join(l for l in src.splitlines() if not l.rstrip().endswith("# yours"))
    exec(compile(code, "README.md (blender recipe)", "exec"), env)


def fresh():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def world_height(objs):
    """Height (Blender's Z, up) of the objects' evaluated meshes in world space, metres."""
    dg = bpy.context.evaluated_depsgraph_get()
    lo, hi = float("inf"), float("-inf")
    for o in objs:
        ev = o.evaluated_get(dg)
        me = ev.to_mesh()
        co = numpy.empty(3 * len(me.vertices), dtype=numpy.float32)
        me.vertices.foreach_get("co", co)
        ev.to_mesh_clear()
        co = co.reshape(-1, 3).astype(numpy.float64)
        w = numpy.c_[co, numpy.ones(len(co))] @ numpy.array(o.matrix_world).T
        lo, hi = min(lo, w[:, 2].min()), max(hi, w[:, 2].max())
    return hi - lo


def local_positions(o):
    dg = bpy.context.evaluated_depsgraph_get()
    ev = o.evaluated_get(dg)
    me = ev.to_mesh()
    co = numpy.empty(3 * len(me.vertices), dtype=numpy.float32)
    me.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    return co.reshape(-1, 3)


def glb_json(path):
    b = open(path, "rb").read()
    magic, _, _ = struct.unpack_from("<III", b, 0)
    n, kind = struct.unpack_from("<II", b, 12)
    assert magic == 0x46546C67 and kind == 0x4E4F534A, "%s: not a GLB" % path
    return json.loads(b[20:20 + n])


def check_glb(a):
    fps, frames, height, tol = float(a["fps"]), int(a["frames"]), float(a["height"]), float(a["tol"])
    doc = glb_json(a["glb"])
    named = doc.get("asset", {}).get("extras", {}).get("frameRate")
    assert named is not None and abs(named - fps) < 1e-9 * fps, \
        "glb: asset.extras.frameRate %r, want %g" % (named, fps)
    fresh()
    bpy.ops.import_scene.gltf(filepath=a["glb"])
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    assert meshes, "glb: no mesh imported"
    h = world_height(meshes)
    say("glb: imported %d mesh object(s) under %s; world height %.4f m (want %.3f m +- %g%%)"
        % (len(meshes), [o.parent.name for o in meshes if o.parent], h, height, 100 * tol))
    assert abs(h - height) <= tol * height, "glb: height %.4f m, want %.3f m" % (h, height)
    # the keys: the take's duration at whatever rate the scene has (Blender: time x scene fps)
    scene = bpy.context.scene
    sfps = scene.render.fps / scene.render.fps_base
    spans = [a.frame_range[1] - a.frame_range[0] for a in bpy.data.actions]
    want = (frames - 1) / fps * sfps
    say("glb: shape-key keys span %s scene frames at %g fps (want %.4g: %d frames at %g fps)"
        % (["%.4g" % s for s in spans], sfps, want, frames, fps))
    assert spans and all(abs(s - want) < 1e-3 * max(want, 1) for s in spans), "glb: key span"
    check_glb_shapes(a, doc, meshes[0], scene, sfps)


def glb_times(path, doc):
    """The animation's key times (seconds), read from the GLB's BIN chunk."""
    b = open(path, "rb").read()
    n = struct.unpack_from("<I", b, 12)[0]
    acc = doc["accessors"][doc["animations"][0]["samplers"][0]["input"]]
    view = doc["bufferViews"][acc["bufferView"]]
    off = 20 + n + 8 + view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    return numpy.frombuffer(b, dtype="<f4", count=acc["count"], offset=off).astype(numpy.float64)


def check_glb_shapes(a, doc, face, scene, sfps):
    """The glb as Blender plays it, at the take's moving frames (its times x the scene's rate),
    against the PC2 (the take's frames bit for bit: fp-export-check): every vertex within
    --max-error (mesh units x the root scale, Blender's axes: glTF (x, y, z) is (x, -z, y)).
    Blender 3.4 clamps each shape key to its slider range, [0, 1] (widened only by the first
    key's weight): a negative weight played as 0, the face 27 mm off at some frames."""
    cache, scale = read_pc2(a["pc2"]), float(a["scale"])
    src = doc["meshes"][0].get("extras", {}).get("sourceVertex")   # (absent: glTF vertex j is j)
    src = numpy.array(src if src is not None else range(cache.shape[1]))
    times = glb_times(a["glb"], doc)
    tol_units = float(a.get("max_error_mm", "0.1")) * 1.001 / (1000 * scale) + 1e-6 * float(numpy.abs(cache).max())
    ks = [0] + moving_frames(cache, 1e-6 * float(numpy.abs(cache).max()), count=12) + [len(cache) - 1]
    worst = 0.0
    for k in ks:
        fr = times[k] * sfps
        scene.frame_set(int(numpy.floor(fr)), subframe=float(fr - numpy.floor(fr)))
        co = local_positions(face).astype(numpy.float64)
        got = (numpy.c_[co, numpy.ones(len(co))] @ numpy.array(face.matrix_world).T)[:, :3]
        assert len(got) == len(src), "glb: Blender has %d vertices, the file %d" % (len(got), len(src))
        v = cache[k][src].astype(numpy.float64)
        want = numpy.c_[v[:, 0], -v[:, 2], v[:, 1]] * scale
        e = float(numpy.linalg.norm(got - want, axis=1).max()) / scale
        worst = max(worst, e)
        assert e <= tol_units, "glb: at the take's frame %d (scene frame %.3f) Blender's face is %.4g " \
            "mesh units (%.4g mm) from the take's (limit %.4g)" % (k, fr, e, e * 1000 * scale, tol_units)
    say("glb: Blender's shapes at the take's frames %s within %.4g mesh units of the take's "
        "(largest %.4g)" % (ks, tol_units, worst))


def read_pc2(path):
    b = open(path, "rb").read()
    assert b[:12] == b"POINTCACHE2\0", "%s: not PC2" % path
    _, points, _, _, samples = struct.unpack_from("<iiffi", b, 12)
    return numpy.frombuffer(b, dtype="<f4", offset=32).reshape(samples, points, 3)


def moving_frames(cache, tol, count=4):
    """Frames k (0 < k < F-1) where the face differs from both neighbours by more than 100 x
    tol, the ones that move most first."""
    d = numpy.abs(numpy.diff(cache, axis=0)).max(axis=(1, 2))   # d[k]: frame k+1 vs k
    both = numpy.minimum(d[:-1], d[1:])                        # frame k = i+1
    order = [int(i) + 1 for i in numpy.argsort(-both) if both[i] > 100 * tol]
    return sorted(order[:count])


def import_with_recipe(a, blocks, cache_path, rate, frames, scale):
    fresh()
    env = {"OBJ": a["obj"], "CACHE": cache_path, "RATE": rate, "FRAMES": frames, "SCALE": scale}
    run_block(blocks["blender-recipe"], env)
    return env


def check_pc2(a, blocks):
    fps, frames, scale = float(a["fps"]), int(a["frames"]), float(a["scale"])
    height, tol_h = float(a["height"]), float(a["tol"])
    r = Fraction(a["fps"]).limit_denominator(1001)
    env = import_with_recipe(a, blocks, a["pc2"], (r.numerator, r.denominator), frames, scale)
    scene, face = env["scene"], env["face"]
    cache = read_pc2(a["pc2"])
    assert cache.shape[0] == frames, "pc2: %d samples, want %d" % (cache.shape[0], frames)
    sfps = scene.render.fps / scene.render.fps_base
    span = scene.frame_end - scene.frame_start + 1
    tol = 1e-6 * float(numpy.abs(cache).max())
    ks = [0] + moving_frames(cache, tol, count=8) + [frames - 1]
    assert len(ks) > 2, "pc2: the take does not move from frame to frame (nothing to tell apart)"
    worst = 0.0
    for k in ks:
        scene.frame_set(scene.frame_start + k)
        got = local_positions(face)
        assert got.shape == cache[k].shape, "pc2: %s vertices, want %s" % (got.shape, cache[k].shape)
        e = float(numpy.abs(got - cache[k]).max())
        worst = max(worst, e)
        assert e <= tol, "pc2: scene frame %d is %.3g from the take's frame %d" % (
            scene.frame_start + k, e, k)
        for j in (k - 1, k + 1):
            if 0 <= j < frames and k not in (0, frames - 1):
                assert float(numpy.abs(got - cache[j]).max()) > 10 * tol, \
                    "pc2: scene frame %d also matches the take's frame %d" % (scene.frame_start + k, j)
    scene.frame_set(scene.frame_start)
    h = world_height([face])
    say("pc2: the README's recipe: scene at %g fps, frames %d-%d (%d frames, %.4f s; the take "
        "%d frames at %g fps, %.4f s); scene frame %d+k shows the take's frame k for k in %s "
        "(largest difference %.3g mesh units, tolerance %.3g); world height %.4f m"
        % (sfps, scene.frame_start, scene.frame_end, span, span / sfps, frames, fps,
           frames / fps, scene.frame_start, ks, worst, tol, h))
    assert abs(sfps - fps) < 1e-9 * fps, "pc2: scene at %g fps, want %g" % (sfps, fps)
    assert span == frames, "pc2: scene has %d frames, want %d" % (span, frames)
    assert abs(h - height) <= tol_h * height, "pc2: height %.4f m, want %.3f m" % (h, height)


def read_mdd(path):
    b = open(path, "rb").read()
    frames, points = struct.unpack_from(">ii", b, 0)
    times = numpy.frombuffer(b, dtype=">f4", count=frames, offset=8)
    pos = numpy.frombuffer(b, dtype=">f4", offset=8 + 4 * frames).reshape(frames, points, 3)
    return times, pos


def check_mdd(a, blocks):
    fps, frames, scale = float(a["fps"]), int(a["frames"]), float(a["scale"])
    r = Fraction(a["fps"]).limit_denominator(1001)
    env = import_with_recipe(a, blocks, a["mdd"], (r.numerator, r.denominator), frames, scale)
    scene, face = env["scene"], env["face"]
    scene.render.fps, scene.render.fps_base = 24, 1           # a scene at another rate
    run_block(blocks["blender-recipe-mdd-time"], env)
    times, cache = read_mdd(a["mdd"])
    tol = 1e-6 * float(numpy.abs(cache).max())
    moving = set(moving_frames(cache, tol, count=frames))
    checked = []
    for f in range(0, int((frames - 1) / fps * 24) + 1):
        k = Fraction(f) / 24 * r                              # the take's frame at f / 24 s
        if k.denominator != 1 or int(k) >= frames:
            continue
        k = int(k)
        scene.frame_set(scene.frame_start + f)
        got = local_positions(face)
        e = float(numpy.abs(got - cache[k]).max())
        assert e <= tol, "mdd: scene frame %d (%.4f s) is %.3g from the take's frame %d" % (
            scene.frame_start + f, f / 24, e, k)
        if k in moving:
            for j in (k - 1, k + 1):
                assert float(numpy.abs(got - cache[j]).max()) > 10 * tol, \
                    "mdd: scene frame %d also matches the take's frame %d" % (scene.frame_start + f, j)
        checked.append((scene.frame_start + f, k))
    assert len([c for c in checked if c[1] in moving]) >= 2, "mdd: too few moving frames checked"
    say("mdd: Time Mode Time in a 24 fps scene: scene frame -> take frame %s (each within %.3g "
        "mesh units; times %.4f .. %.4f s)" % (checked, tol, times[0], times[-1]))


def world_positions(o):
    co = local_positions(o).astype(numpy.float64)
    return (numpy.c_[co, numpy.ones(len(co))] @ numpy.array(o.matrix_world).T)[:, :3]


def check_gltf_face(a, blocks):
    """The README's recipe for a take whose mesh is a glTF (--face, a GLB written by `pose`):
    the face imported from it, the cache (--face-pc2) on it; scene frame start + k is the
    take's frame k in Blender's world (glTF (x, y, z) is (x, -z, y), x --face-scale) at the
    take's moving frames, and not its neighbours."""
    fps, frames, scale = float(Fraction(a["face-fps"])), int(a["face-frames"]), float(a["face-scale"])
    r = Fraction(a["face-fps"]).limit_denominator(1001)
    fresh()
    env = {"FACE": a["face"], "CACHE": a["face-pc2"], "RATE": (r.numerator, r.denominator),
           "FRAMES": frames, "SCALE": scale}
    run_block(blocks["blender-recipe-gltf-face"], env)
    scene, face = env["scene"], env["face"]
    cache = read_pc2(a["face-pc2"]).astype(numpy.float64)
    assert cache.shape[0] == frames, "gltf face: %d samples, want %d" % (cache.shape[0], frames)
    world = numpy.stack([cache[..., 0], -cache[..., 2], cache[..., 1]], axis=-1) * scale
    tol = 1e-6 * float(numpy.abs(world).max())
    ks = [0] + moving_frames(cache * scale, tol, count=8) + [frames - 1]
    assert len(ks) > 2, "gltf face: the take does not move from frame to frame"
    worst = 0.0
    for k in ks:
        scene.frame_set(scene.frame_start + k)
        got = world_positions(face)
        assert got.shape == world[k].shape, "gltf face: %s vertices, want %s" % (got.shape, world[k].shape)
        e = float(numpy.linalg.norm(got - world[k], axis=1).max())
        worst = max(worst, e)
        assert e <= tol, "gltf face: scene frame %d is %.4g m from the take's frame %d" % (
            scene.frame_start + k, e, k)
        for j in (k - 1, k + 1):
            if 0 <= j < frames and k not in (0, frames - 1):
                assert float(numpy.abs(got - world[j]).max()) > 10 * tol, \
                    "gltf face: scene frame %d also matches the take's frame %d" % (scene.frame_start + k, j)
    say("gltf face: the README's glTF-face recipe: scene frame %d+k shows the take's frame k in "
        "metres, Z-up, for k in %s (largest %.3g m, tolerance %.3g)" % (scene.frame_start, ks, worst, tol))


def check_glb_rate(a, blocks):
    """--face-glb (a take at --face-fps, 30000/1001) imported into a 29.97 fps scene (30 /
    1.001), then the README's block that moves the keys: the keys span frames - 1 scene
    frames, and the shapes at each frame's time x the scene's rate are the take's (Blender
    3.4 keys at t x 30 without the block: 1.86 mm off by frame 81)."""
    fps, frames = float(Fraction(a["face-fps"])), int(a["face-frames"])
    fresh()
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 30, 1.001
    bpy.ops.import_scene.gltf(filepath=a["face-glb"])
    run_block(blocks["blender-recipe-gltf-rate"], {})
    sfps = scene.render.fps / scene.render.fps_base
    spans = [x.frame_range[1] - x.frame_range[0] for x in bpy.data.actions]
    want = (frames - 1) / fps * sfps
    say("glb at %.5g fps: keys span %s scene frames of a %.5g fps scene (want %.5g)"
        % (fps, ["%.5g" % x for x in spans], sfps, want))
    assert spans and all(abs(x - want) < 1e-3 for x in spans), "glb at 29.97 fps: key span"
    faces = [o for o in bpy.data.objects if o.type == "MESH"]
    b = {"glb": a["face-glb"], "pc2": a["face-pc2"], "scale": a["face-scale"]}
    check_glb_shapes(b, glb_json(a["face-glb"]), faces[0], scene, sfps)


def main():
    a = args()
    blocks = recipe_blocks(a["readme"])
    check_glb(a)
    check_pc2(a, blocks)
    check_mdd(a, blocks)
    if "face" in a:
        check_gltf_face(a, blocks)
        check_glb_rate(a, blocks)
    say("PASS")


main()
