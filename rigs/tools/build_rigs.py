#!/usr/bin/env python3
"""Build rigs/*.json from the neutral meshes in ../shared/data/faces (rigs/README.md).

Usage: python3 rigs/tools/build_rigs.py [SHARED_DATA_DIR]   (default: ../shared/data)
Needs python3 with numpy and scipy (Debian python3-scipy). Deterministic: same meshes in,
same files out (no randomness; sorted sets; fixed number formatting).

What is derived from geometry, and how (anatomy in rigs/README.md):
  ICT FaceKit: the part index ranges of its README (teeth, eyeballs, gums and tongue),
    the upper/lower split of "gums and tongue" by the nearest tooth (upper or lower set),
    the cranium as the skin above the brows (1.2 cm above the highest brow landmark) and
    behind the ears above the neck, the ears as the lateral protrusions around the ear canal.
    Landmarks from the README's Multi-PIE 68 list. Hinge, mouth line, menton, gonion from
    the anatomy of the neutral head (see README "ICT: how the hinge and falloff were chosen").
  MediaPipe canonical: landmark indices of MediaPipe's face mesh (face_mesh_regions.txt),
    skull = forehead above the brows; jaw = the chin's bony prominence (skin over the
    mental protuberance, within 1 cm of the chin landmark).
  Lee Perry-Smith: a similarity map from the ICT head (nose tip and chin-to-crown height)
    carries the ICT landmarks, hinge and falloff points over; each landmark is the nearest
    vertex; skull and jaw as for MediaPipe.
"""
import json, sys, zlib
from pathlib import Path
import numpy as np
from scipy.spatial import cKDTree


def load_obj(path):
    V, F = [], []
    for line in open(path):
        if line.startswith('v '):
            V.append([float(x) for x in line.split()[1:4]])
        elif line.startswith('f '):
            idx = [int(t.split('/')[0]) - 1 for t in line.split()[1:]]
            for k in range(1, len(idx) - 1):
                F.append([idx[0], idx[k], idx[k + 1]])
    return np.array(V, dtype=np.float32), np.array(F)


def crc(V):
    return '%08x' % (zlib.crc32(V.astype('<f4').tobytes()) & 0xffffffff)


def ranges(idx):
    """Sorted vertex indices -> compact list of ints and [first, last] ranges."""
    idx = sorted(set(int(i) for i in idx))
    out, i = [], 0
    while i < len(idx):
        j = i
        while j + 1 < len(idx) and idx[j + 1] == idx[j] + 1:
            j += 1
        out.append(idx[i] if i == j else [idx[i], idx[j]])
        i = j + 1
    return out


def r3(p):
    return [round(float(x), 4) for x in p]


def rig(name, desc, mesh_name, V, mm, regions, landmarks, hinge, open_deg, glide, falloff, ramp):
    n = len(V)
    used = set()
    regs = []
    for rname, kind, idx in regions:
        s = sorted(set(int(i) for i in idx) - used)
        used |= set(s)
        if s:
            regs.append({"name": rname, "kind": kind, "vertices": ranges(s)})
    rest = sorted(set(range(n)) - used)
    if rest:
        regs.append({"name": "soft_tissue", "kind": "soft", "vertices": ranges(rest)})
    return {
        "format": "facepuppet-rig", "version": 1, "name": name, "description": desc,
        "mesh": {"name": mesh_name, "vertex_count": n, "positions_crc32": crc(V)},
        "mm_per_unit": mm,
        "axes": {"up": [0, 1, 0], "forward": [0, 0, 1], "left": [1, 0, 0]},
        "regions": regs,
        "landmarks": {k: int(v) for k, v in landmarks.items()},
        "jaw": {"hinge": {"right": r3(hinge[0]), "left": r3(hinge[1])}, "open_degrees": open_deg,
                "glide": glide, "falloff": falloff},
        "mobility": {"ramp": ramp},
        "channels": [{"name": "jaw.open", "min": 0, "max": 1, "neutral": 0}],
    }


def write(path, obj):
    text = json.dumps(obj, indent=1, separators=(',', ': '))
    # keep vertex lists on one line each: collapse the innermost number arrays
    import re
    text = re.sub(r'\[\s+(-?[\d.]+),\s+(-?[\d.]+)\s+\]', r'[\1, \2]', text)
    text = re.sub(r'\[\s+(-?[\d.]+),\s+(-?[\d.]+),\s+(-?[\d.]+)\s+\]', r'[\1, \2, \3]', text)
    Path(path).write_text(text + '\n')


# Multi-PIE 68 (ICT README), 0-based; index k here is point k+1 of Multi-PIE.
ICT_MP68 = [1225, 1888, 1052, 367, 1719, 1722, 2199, 1447, 966, 3661, 4390, 3927, 3924, 2608,
            3272, 4088, 3443, 268, 493, 1914, 2044, 1401, 3615, 4240, 4114, 2734, 2509, 978, 4527,
            4942, 4857, 1140, 2075, 1147, 4269, 3360, 1507, 1542, 1537, 1528, 1518, 1511, 3742,
            3751, 3756, 3721, 3725, 3732, 5708, 5695, 2081, 0, 4275, 6200, 6213, 6346, 6461, 5518,
            5957, 5841, 5702, 5711, 5533, 6216, 6207, 6470, 5517, 5966]


def ict_landmarks():
    P = lambda k: ICT_MP68[k - 1]
    return {
        "chin": P(9), "nose_tip": P(31), "nose_bridge": P(28),
        "upper_lip": P(52), "lower_lip": P(58), "upper_lip_inner": P(63), "lower_lip_inner": P(67),
        # x < 0 is the face's right (left = +x)
        "mouth_corner_right": P(49), "mouth_corner_left": P(55),
        "brow_right": P(20), "brow_left": P(25), "brow_inner_right": P(22), "brow_inner_left": P(23),
        "brow_outer_right": P(18), "brow_outer_left": P(27),
        "eye_outer_right": P(37), "eye_inner_right": P(40), "eye_inner_left": P(43), "eye_outer_left": P(46),
        "jaw_right": P(5), "jaw_left": P(13), "cheek_right": P(3), "cheek_left": P(15),
    }


# The soft-tissue falloff (rigs/README.md "ICT: how the hinge and falloff were chosen").
ICT_CHEEK_BAND = float(__import__('os').environ.get('FP_CHEEK_BAND', 2.2))
ICT_CHEEK_DISTANCE = float(__import__('os').environ.get('FP_CHEEK_DISTANCE', 1.0))
ICT_CORNER_INSET = float(__import__('os').environ.get('FP_CORNER_INSET', 1.0))
ICT_INNER_DEPTH = float(__import__('os').environ.get('FP_INNER_DEPTH', 0.8))
ICT_NECK_BAND = float(__import__('os').environ.get('FP_NECK_BAND', 7.0))
ICT_SOCKET_RATIO = float(__import__('os').environ.get('FP_SOCKET_RATIO', 0.5))
# Mobility ramp: fingers act fully this far from bone; the finger clamp is ramp / 3 (fp_rig.h).
ICT_RAMP = 1.0
ICT_BACK_BAND = float(__import__('os').environ.get('FP_BACK_BAND', 4.0))


def build_ict(data):
    mesh = 'faces/ict-facekit/generic_neutral_mesh.obj'
    V, F = load_obj(data / mesh)
    lm = ict_landmarks()
    skin = np.arange(0, 11248)
    S = V[skin]
    brow_top = max(V[lm[k]][1] for k in ("brow_right", "brow_left", "brow_inner_right", "brow_inner_left"))
    cranium = skin[(S[:, 1] > brow_top + 1.2) | ((S[:, 2] < -2.5) & (S[:, 1] > -1.0))]
    ears = skin[(np.abs(S[:, 0]) > 7.3) & (S[:, 1] > -2.6) & (S[:, 1] < 6.2) & (S[:, 2] > -2.3) & (S[:, 2] < 2.9)]
    upper_teeth = np.arange(17039, 19247)
    lower_teeth = np.arange(19247, 21451)
    gums = np.arange(14062, 17039)
    du, _ = cKDTree(V[upper_teeth]).query(V[gums])
    dl, _ = cKDTree(V[lower_teeth]).query(V[gums])
    eyeballs = np.arange(21451, 24591)
    # The mouth's lining: the part next to the lower gums and teeth is the floor of the mouth
    # and moves with the mandible (jaw), the part next to the upper ones is the palate and the
    # upper vestibule (skull); the band between stays soft and takes the falloff.
    socket = np.arange(11248, 13294)
    upper = np.r_[upper_teeth, gums[du < dl]]
    lower = np.r_[lower_teeth, gums[du >= dl]]
    su, _ = cKDTree(V[upper]).query(V[socket])
    sl, _ = cKDTree(V[lower]).query(V[socket])
    socket_jaw = socket[sl < ICT_SOCKET_RATIO * su]
    socket_skull = socket[su < ICT_SOCKET_RATIO * sl]
    regions = [
        ("cranium", "skull", cranium), ("ears", "skull", ears),
        ("upper_teeth", "skull", upper_teeth), ("upper_gums", "skull", gums[du < dl]),
        ("eyeballs", "skull", eyeballs),
        ("lower_teeth", "jaw", lower_teeth), ("lower_gums_tongue", "jaw", gums[du >= dl]),
        ("mouth_floor", "jaw", socket_jaw), ("palate", "skull", socket_skull),
        ("face", "soft", np.arange(0, 9409)), ("head_neck", "soft", np.arange(9409, 11248)),
        ("mouth_socket", "soft", np.arange(11248, 13294)), ("eye_sockets", "soft", np.arange(13294, 14062)),
        ("eye_surfaces", "soft", np.arange(24591, 25351)), ("eyelashes", "soft", np.arange(25351, 26719)),
    ]
    # Hinge: the condyles, 1.3 cm in front of the ear canal at its height, 1.9 cm under the
    # skin (intercondylar distance about 10 cm).
    hinge = ([-5.0, 0.5, 2.3], [5.0, 0.5, 2.3])
    mouth = [V[lm["mouth_corner_right"]],
             0.5 * (V[5711] + V[5966]), 0.5 * (V[lm["upper_lip_inner"]] + V[lm["lower_lip_inner"]]),
             0.5 * (V[6216] + V[6470]), V[lm["mouth_corner_left"]]]
    falloff = {"mouth_line": [r3(p) for p in mouth], "lip_band": 0.05, "cheek_band": ICT_CHEEK_BAND,
               "cheek_distance": ICT_CHEEK_DISTANCE, "corner_inset": ICT_CORNER_INSET,
               "inner_depth": ICT_INNER_DEPTH, "menton": [0.0, -8.0, 9.2], "gonion": [5.3, -5.0, 1.6],
               "neck_band": ICT_NECK_BAND, "back_band": ICT_BACK_BAND}
    return rig("ict-facekit", "ICT FaceKit generic neutral head (cm): skull, jaw, falloff from anatomy",
               mesh, V, 10.0, regions, lm, hinge, 26.0, [0.0, 0.0], falloff, ICT_RAMP), V, F


def build_mediapipe(data):
    mesh = 'faces/mediapipe-canonical/canonical_face_model.obj'
    V, F = load_obj(data / mesh)
    # MediaPipe face mesh indices (x < 0 is the face's right)
    lm = {"chin": 152, "nose_tip": 1, "nose_bridge": 6, "upper_lip": 0, "lower_lip": 17,
          "upper_lip_inner": 13, "lower_lip_inner": 14, "mouth_corner_right": 61, "mouth_corner_left": 291,
          "brow_right": 105, "brow_left": 334, "brow_inner_right": 107, "brow_inner_left": 336,
          "brow_outer_right": 70, "brow_outer_left": 300,
          "eye_outer_right": 33, "eye_inner_right": 133, "eye_inner_left": 362, "eye_outer_left": 263,
          "jaw_right": 172, "jaw_left": 397, "forehead": 10}
    brow_top = max(V[lm[k]][1] for k in ("brow_right", "brow_left"))
    idx = np.arange(len(V))
    cranium = idx[V[:, 1] > brow_top + 1.0]
    chin = idx[np.linalg.norm(V - V[lm["chin"]], axis=1) < 1.6]
    regions = [("forehead", "skull", cranium), ("chin_bone", "jaw", chin)]
    hinge = ([-6.2, -0.5, -2.0], [6.2, -0.5, -2.0])
    mouth = [V[61], 0.5 * (V[13] + V[14]), V[291]]
    falloff = {"mouth_line": [r3(p) for p in mouth], "lip_band": 0.05, "cheek_band": 1.8,
               "cheek_distance": 2.0, "menton": [0.0, -9.2, 4.0], "gonion": [5.9, -6.0, -0.8],
               "neck_band": 2.5, "back_band": 1.2}
    return rig("mediapipe-canonical", "MediaPipe canonical face mask (cm); hinge behind the mask",
               mesh, V, 10.0, regions, lm, hinge, 26.0, [0.0, 0.0], falloff, ICT_RAMP), V, F


def build_lps(data, ict_rig, Vi):
    mesh = 'faces/lee-perry-smith/LeePerrySmith.obj'
    V, F = load_obj(data / mesh)
    # similarity from ICT: nose tips coincide; scale = ratio of nose-tip-to-crown heights
    ni = Vi[ict_rig["landmarks"]["nose_tip"]]
    nl = V[np.argmax(V[:, 2])]
    s = (V[:, 1].max() - nl[1]) / (Vi[:11248, 1].max() - ni[1])
    T = lambda p: (np.asarray(p) - ni) * s + nl
    face = V[:, 2] > T([0, 0, 6.0])[2]          # front-facing part for landmark snapping
    idx = np.arange(len(V))
    tree = cKDTree(V[face])
    lm = {}
    for k, v in ict_rig["landmarks"].items():
        _, j = tree.query(T(Vi[v]))
        lm[k] = int(idx[face][j])
    mm = 10.0 / s
    brow_top = max(V[lm[k]][1] for k in ("brow_right", "brow_left"))
    cranium = idx[(V[:, 1] > brow_top + 1.2 * s) | ((V[:, 2] < T([0, 0, -2.5])[2]) & (V[:, 1] > T([0, -1.0, 0])[1]))]
    chin = idx[(np.linalg.norm(V - V[lm["chin"]], axis=1) < 1.0 * s)]
    regions = [("cranium", "skull", cranium), ("chin_bone", "jaw", chin)]
    h = ict_rig["jaw"]["hinge"]
    fo = dict(ict_rig["jaw"]["falloff"])
    fo["mouth_line"] = [r3(V[lm["mouth_corner_right"]]),
                        r3(0.5 * (V[lm["upper_lip_inner"]] + V[lm["lower_lip_inner"]])),
                        r3(V[lm["mouth_corner_left"]])]
    for k in ("menton", "gonion"):
        fo[k] = r3(T(fo[k]))
    for k in ("lip_band", "cheek_band", "cheek_distance", "corner_inset", "inner_depth", "neck_band", "back_band"):
        fo[k] = round(fo[k] * s, 4)
    return rig("lee-perry-smith", "Lee Perry-Smith head scan; landmarks and hinge carried over from ICT by a similarity",
               mesh, V, round(mm, 4), regions, lm, (T(h["right"]), T(h["left"])), 26.0, [0.0, 0.0], fo,
               round(ICT_RAMP * s, 4)), V, F


def main():
    data = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / '../shared/data')
    out = Path(__file__).resolve().parents[1]
    ict, Vi, _ = build_ict(data)
    write(out / 'ict-facekit.json', ict)
    write(out / 'mediapipe-canonical.json', build_mediapipe(data)[0])
    write(out / 'lee-perry-smith.json', build_lps(data, ict, Vi)[0])


if __name__ == '__main__':
    main()
