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
import scipy.sparse as sp
import scipy.sparse.csgraph as csg
from scipy.sparse.linalg import spsolve


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


def rig(name, desc, mesh_name, V, mm, regions, landmarks, hinge, kin, falloff, ramp):
    """kin: (open_degrees, [forward, down] glide, glide_start) of the jaw."""
    open_deg, glide, glide_start = kin
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
        "mesh": {"name": mesh_name, "vertex_count": n, "positions_crc32": crc(V),
                 # where the landmarks lie on this mesh: a moved copy of it gets the rig
                 # carried there by the similarity that fits them (fp_rig_placement)
                 "landmark_positions": {k: r3(V[int(v)]) for k, v in landmarks.items()}},
        "mm_per_unit": mm,
        "axes": {"up": [0, 1, 0], "forward": [0, 0, 1], "left": [1, 0, 0]},
        "regions": regs,
        "landmarks": {k: int(v) for k, v in landmarks.items()},
        "jaw": {"hinge": {"right": r3(hinge[0]), "left": r3(hinge[1])}, "open_degrees": open_deg,
                "glide": glide, "glide_start": glide_start, "falloff": falloff},
        "mobility": {"ramp": ramp},
        "channels": [{"name": "jaw.open", "min": 0, "max": 1, "neutral": 0}],
    }


def write(path, obj):
    values = obj.get("jaw", {}).get("weights", {}).get("values")
    if values is not None:  # 16 numbers a line
        obj["jaw"]["weights"]["values"] = "@VALUES@"
    text = json.dumps(obj, indent=1, separators=(',', ': '))
    if values is not None:
        obj["jaw"]["weights"]["values"] = values
        rows = [', '.join(json.dumps(v) for v in values[i:i + 16]) for i in range(0, len(values), 16)]
        text = text.replace('"@VALUES@"', '[\n    ' + ',\n    '.join(rows) + ']')
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
ICT_CHEEK_BAND = 2.5      # half-width of the cheek blend about the mouth line's height, cm
ICT_CHEEK_DISTANCE = 1.0
ICT_CORNER_INSET = 1.0
ICT_INNER_DEPTH = 0.8
# Under the chin and behind the ramus the weight falls over 1.5 theta r (the injectivity bound,
# README "Falloff"; theta the angle at jaw.open = 1): r the distance from the hinge axis there.
ICT_NECK_R = 11.0         # cm, the skin under the chin
ICT_BACK_R = 5.5          # cm, the skin behind the ramus
# The jaw's arc (rigs/README.md "ICT: how the hinge, the angle and the weights were chosen"):
# Posselt's envelope of motion: the opening is a pure rotation about the condyles for the
# first 20-25 mm of incisal opening, then the condyles also slide forward and down the
# articular eminence until the maximal opening, the slide growing linearly with the angle.
# jaw.open = 1 is a wide opening every healthy adult reaches (JAW_OPEN_MM), on that path.
JAW_ROTATION_ONLY_MM = 22.5   # incisal opening of the pure rotation (20-25 mm)
JAW_MAX_OPENING_MM = 50.0     # adult maximal interincisal opening (40-60 mm; about 50)
JAW_OPEN_MM = 40.0            # jaw.open = 1 (below 40 mm a maximal opening counts as restricted)
JAW_CONDYLE_SLIDE_MM = 15.0   # condylar translation at maximal opening (10-20 mm)
JAW_EMINENCE_DEG = 35.0       # the condyle's path below the Frankfort horizontal (30-40 deg)
# Mobility ramp: fingers act fully this far from bone; the finger clamp is ramp / 3 (fp_rig.h).
ICT_RAMP = 1.0
# Jaw weights of the lips and the mouth's inside (rigs/README.md "ICT: the jaw weights").
ICT_LIP_ZONE = 4.5        # cm along the skin from the lips' inner edge: solved, not the falloff
ICT_LIP_FULL = 0.4        # cm from the midline: the inner lip edges' weights leave 0 / 1 here ...
ICT_LIP_KEEP = 1.0        # ... lip skin nearer the midline than this and farther than
ICT_LIP_KEEP_BAND = 0.5   # this from the mouth line keeps the falloff's 0 (upper) / 1 (lower)
ICT_TEETH_T = (0.3, 0.6)  # t = d_upper / (d_upper + d_lower) teeth: weight 0 below, 1 above
ICT_TEETH_NEAR = 0.5      # cm: lining and gums this near a tooth take smoothstep(t)
ICT_LOOP_CLEAR = 1.0      # cm: ... but not the lining this near its opening (the lips decide there)
ICT_KNN = 6               # nearest neighbours joining the mouth's separate surfaces


def jaw_kinematics(V, hinge, upper_teeth, lower_teeth, mm):
    """The jaw's angle at jaw.open = 1, its glide and where the glide starts, from the
    anatomy constants JAW_* and the mesh's incisors (rigs/README.md): the lower incisal edge
    (the highest lower tooth vertex within 4 mm of the midline) turns about the hinge axis
    (+x, the rig's left) and slides with the condyle; the incisal opening is the upper incisal
    edge's height (the lowest upper tooth vertex near the midline) minus the lower edge's.
    theta_r: the pure rotation that opens JAW_ROTATION_ONLY_MM; theta_max: the rotation that,
    with the whole slide JAW_CONDYLE_SLIDE_MM, opens JAW_MAX_OPENING_MM; between them the
    slide grows linearly with the angle; theta_1: the angle on that path that opens
    JAW_OPEN_MM (jaw.open = 1). Returns (open_degrees = theta_1, [forward, down] glide at
    theta_1 in mesh units, glide_start = theta_r / theta_1, report dict)."""
    H = 0.5 * (np.array(hinge[0], float) + np.array(hinge[1], float))
    L, U = V[lower_teeth].astype(float), V[upper_teeth].astype(float)
    L = L[np.abs(L[:, 0]) < 4.0 / mm]
    U = U[np.abs(U[:, 0]) < 4.0 / mm]
    le, ue = L[np.argmax(L[:, 1])] - H, U[np.argmin(U[:, 1])] - H
    a = np.radians(JAW_EMINENCE_DEG)
    slide = JAW_CONDYLE_SLIDE_MM / mm

    def opening(theta_deg, down):  # mesh units
        t = np.radians(theta_deg)
        y = le[1] * np.cos(t) - le[2] * np.sin(t) - down
        return ue[1] - y

    def solve(f, target):  # f increasing in the angle
        lo, hi = 0.0, 60.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if f(mid) < target else (lo, mid)
        return 0.5 * (lo + hi)
    theta_r = solve(lambda t: opening(t, 0.0), JAW_ROTATION_ONLY_MM / mm)
    theta_max = solve(lambda t: opening(t, slide * np.sin(a)), JAW_MAX_OPENING_MM / mm)
    frac = lambda t: min(1.0, max(0.0, (t - theta_r) / (theta_max - theta_r)))
    theta_1 = solve(lambda t: opening(t, frac(t) * slide * np.sin(a)), JAW_OPEN_MM / mm)
    open_deg = round(theta_1, 1)
    g = frac(open_deg) * slide
    rep = {"theta_r": theta_r, "theta_max": theta_max, "theta_1": theta_1, "slide_1_mm": g * mm,
           "overbite_mm": -opening(0, 0) * mm, "incisor_radius": float(np.hypot(le[1], le[2])),
           "lower_edge": le + H, "upper_edge": ue + H}
    return (open_deg, [round(float(g * np.cos(a)), 3), round(float(g * np.sin(a)), 3)],
            round(theta_r / open_deg, 3), rep)


def smoothstep(a, b, x):
    t = np.clip((np.asarray(x, dtype=float) - a) / (b - a), 0, 1)
    return t * t * (3 - 2 * t)


def expand(vs):
    out = []
    for e in vs:
        out.extend(range(e[0], e[1] + 1) if isinstance(e, list) else [e])
    return np.array(out, dtype=int)


def falloff_weights(rig_obj, V):
    """The jaw weight of every vertex by the rig's falloff, as fp_rig_bind computes it
    (rigs/README.md "Jaw and falloff"); skull 0, jaw 1; jaw.weights not applied."""
    j = rig_obj["jaw"]
    f = j["falloff"]
    ax = rig_obj["axes"]
    up, fwd, left = (np.array(ax[k], dtype=float) for k in ("up", "forward", "left"))
    H = 0.5 * (np.array(j["hinge"]["right"]) + np.array(j["hinge"]["left"]))
    fc = lambda P: ((P - H) @ left, (P - H) @ up, (P - H) @ fwd)
    x, y, z = fc(np.asarray(V, dtype=float))
    mx, my, mz = fc(np.array(f["mouth_line"], dtype=float))
    ym, zm = np.interp(x, mx, my), np.interp(x, mx, mz)
    e = np.where(x <= mx[0], mx[0] - x, np.where(x >= mx[-1], x - mx[-1], -np.minimum(x - mx[0], mx[-1] - x)))
    s = smoothstep(-f.get("corner_inset", 0.0), f["cheek_distance"], e)
    if f.get("inner_depth", 0.0) > 0:
        s = np.maximum(s, smoothstep(f["inner_depth"], 2 * f["inner_depth"], zm - z))
    b = f["lip_band"] + (f["cheek_band"] - f["lip_band"]) * s
    w_mouth = 1 - smoothstep(-b, b, y - ym)

    def side(a, b_, o):  # signed distance from the line a -> b_ in (z, y), positive away from o
        d = np.array([b_[0] - a[0], b_[1] - a[1]])
        nrm = np.array([d[1], -d[0]]) / np.hypot(*d)
        if (o[0] - a[0]) * nrm[0] + (o[1] - a[1]) * nrm[1] > 0:
            nrm = -nrm
        return (z - a[0]) * nrm[0] + (y - a[1]) * nrm[1]
    _, gy, gz = fc(np.array([f["gonion"]], dtype=float))
    _, ny, nz = fc(np.array([f["menton"]], dtype=float))
    C, G, M = (0.0, 0.0), (gz[0], gy[0]), (nz[0], ny[0])
    w = w_mouth * (1 - smoothstep(0, f["back_band"], side(C, G, M))) * (1 - smoothstep(0, f["neck_band"], side(G, M, C)))
    for g in rig_obj["regions"]:
        if g["kind"] != "soft":
            w[expand(g["vertices"])] = 0.0 if g["kind"] == "skull" else 1.0
    return w


def weld(V):
    """canon[v]: the first vertex at v's exact position (OBJ seams are one point)."""
    _, first, inv = np.unique(V, axis=0, return_index=True, return_inverse=True)
    return first[inv.ravel()]


def edge_graph(V, F, lengths=True):
    E = np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]
    val = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1) if lengths else np.ones(len(E))
    G = sp.coo_matrix((val, (E[:, 0], E[:, 1])), shape=(len(V), len(V))).tocsr()
    return G.maximum(G.T)


def cotan_weights(V, F):
    """Symmetric cotangent weights (the surface Laplacian's), clamped to >= 1e-3 so the
    maximum principle holds on obtuse triangles."""
    I, J, W = [], [], []
    for k in range(3):
        a, b, c = F[:, k], F[:, (k + 1) % 3], F[:, (k + 2) % 3]
        u, v = V[b] - V[a], V[c] - V[a]
        I.append(b), J.append(c)
        W.append(0.5 * (u * v).sum(1) / np.maximum(np.linalg.norm(np.cross(u, v), axis=1), 1e-12))
    A = sp.coo_matrix((np.concatenate(W), (np.concatenate(I), np.concatenate(J))), shape=(len(V), len(V))).tocsr()
    A = A + A.T
    A.data = np.maximum(A.data, 1e-3)
    return A


def boundary_vertices(F, n):
    """Vertices on an edge that only one triangle of F has."""
    E = np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1)
    key = E[:, 0].astype(np.int64) * n + E[:, 1]
    u, cnt = np.unique(key, return_counts=True)
    once = u[cnt == 1]
    return np.unique(np.r_[once // n, once % n]).astype(int)


def ict_jaw_weights(V, F, rig_obj, lm):
    """Jaw weights of the ICT head's lips and mouth inside (rigs/README.md "ICT: the jaw
    weights"): a harmonic interpolation (cotangent weights on the skin, lining, gums and
    tongue; their separate surfaces joined by nearest neighbours) between fixed values:
    the skull 0 and the lower teeth 1; the lips' inner edges (upper 0, lower 1 near the
    midline, both 1/2 at the corners); the lip skin near the midline and all skin farther
    than ICT_LIP_ZONE from the lips' inner edge keep the falloff; lining and gums near the
    teeth take smoothstep(t) of their distances to the upper and lower teeth.
    Returns (w, exact): w for every vertex, exact: the interior vertices fixed at 0 or 1
    by the teeth (rigid with the skull or the jaw)."""
    n = len(V)
    Vd = V.astype(float)
    canon = weld(V)
    idx = np.arange(n)
    face, skin = idx < 9409, idx < 11248
    sock, gums = (idx >= 11248) & (idx < 13294), (idx >= 14062) & (idx < 17039)
    inter = sock | gums
    upper_teeth, lower_teeth = np.arange(17039, 19247), np.arange(19247, 21451)
    w_fall = falloff_weights(rig_obj, V)
    X = Vd[:, 0]
    ML = np.array(rig_obj["jaw"]["falloff"]["mouth_line"])
    ym, zm = np.interp(X, ML[:, 0], ML[:, 1]), np.interp(X, ML[:, 0], ML[:, 2])
    # the lips' inner edges: the face's and the lining's boundary loops at the mouth
    near_mouth = lambda b: b[(np.abs(X[b]) < ML[-1, 0] + 0.5) & (np.abs(Vd[b, 1] - ym[b]) < 0.8) & (Vd[b, 2] > zm[b] - 1.5)]
    floop = near_mouth(boundary_vertices(F[np.all(face[F], axis=1)], n))
    sloop = near_mouth(boundary_vertices(F[np.all(sock[F], axis=1)], n))
    # upper or lower lip: nearer (along the face) to the upper or the lower inner lip landmark
    Gf = edge_graph(Vd, canon[F[np.all(face[F], axis=1)]])
    d_up, d_lo = csg.dijkstra(Gf, directed=False, indices=[canon[lm["upper_lip_inner"]], canon[lm["lower_lip_inner"]]])
    f_up = (d_up[canon] < d_lo[canon])[floop]
    s_up = f_up[cKDTree(Vd[floop]).query(Vd[sloop])[1]]
    x_tip = np.abs(X[floop]).max()
    Gs = edge_graph(Vd, canon[F[np.all(skin[F], axis=1)]])
    d_loop = csg.dijkstra(Gs, directed=False, indices=np.unique(canon[floop])).min(0)[canon]
    du = cKDTree(Vd[upper_teeth]).query(Vd)[0]
    dl = cKDTree(Vd[lower_teeth]).query(Vd)[0]
    t_teeth = smoothstep(*ICT_TEETH_T, du / (du + dl))
    d_sloop = cKDTree(Vd[sloop]).query(Vd)[0]

    fixed, val = np.zeros(n, bool), np.zeros(n)

    def fix(mask, v):
        m = mask & ~fixed
        fixed[m] = True
        val[m] = v[m] if isinstance(v, np.ndarray) else v
    for g in rig_obj["regions"]:  # the skull 0, the jaw 1
        if g["kind"] != "soft":
            m = np.zeros(n, bool)
            m[expand(g["vertices"])] = True
            fix(m, w_fall)
    fix(~(skin | inter), w_fall)  # eyes, lashes, teeth: the falloff (0 there)
    for loop, is_up in ((floop, f_up), (sloop, s_up)):
        # s: 0 at the corners, 1 within ICT_LIP_FULL of the midline; smooth (flat) on the upper
        # lip, which lies on the upper incisors, linear on the lower lip (the least shear)
        ax = np.abs(X[loop])
        s_upper = 1 - smoothstep(ICT_LIP_FULL, x_tip, ax)
        s_lower = np.clip((x_tip - ax) / (x_tip - ICT_LIP_FULL), 0, 1)
        fixed[loop] = True
        val[loop] = np.where(is_up, 0.5 * (1 - s_upper), 0.5 * (1 + s_lower))
    fix(skin & (d_loop > ICT_LIP_ZONE), w_fall)
    fix(face & (np.abs(X) < ICT_LIP_KEEP) & (np.abs(Vd[:, 1] - ym) > ICT_LIP_KEEP_BAND) & ((w_fall == 0) | (w_fall == 1)), w_fall)
    near = np.minimum(du, dl) < ICT_TEETH_NEAR
    fix(gums & near, t_teeth)
    fix(sock & near & (d_sloop > ICT_LOOP_CLEAR), t_teeth)
    exact = inter & fixed & ((val == 0) | (val == 1))
    # the graph: cotangent weights on the surfaces, nearest neighbours across the mouth's parts
    tri = F[np.all((skin | inter)[F], axis=1)]
    A = cotan_weights(Vd, canon[tri])
    iv = idx[inter]
    _, nb = cKDTree(Vd[iv]).query(Vd[iv], k=ICT_KNN + 1)
    K = sp.coo_matrix((np.ones(len(iv) * ICT_KNN), (canon[np.repeat(iv, ICT_KNN)], canon[iv[nb[:, 1:].ravel()]])), shape=(n, n)).tocsr()
    A = (A + K + K.T).tocsr()
    A = (A - sp.diags(A.diagonal())).tocsr()
    # solve on the welded vertices: L_ff w_f = -L_fc w_c
    fc, vc = np.zeros(n, bool), np.zeros(n)
    fc[canon[fixed]], vc[canon[fixed]] = True, val[fixed]
    used = np.zeros(n, bool)
    used[canon[tri]] = used[canon[iv]] = True
    fc |= ~used | (canon != idx)
    L = sp.diags(np.asarray(A.sum(1)).ravel()) - A
    free, con = np.where(~fc)[0], np.where(fc)[0]
    w = vc.copy()
    w[free] = spsolve(L[free][:, free].tocsc(), -L[free][:, con] @ vc[con])
    w = np.clip(w[canon], 0, 1)
    w[fixed] = val[fixed]
    return w, exact


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
    eyeballs = np.arange(21451, 24591)
    socket = np.arange(11248, 13294)
    # Hinge: the condyles, 1.3 cm in front of the ear canal at its height, 1.9 cm under the
    # skin (intercondylar distance about 10 cm).
    hinge = ([-5.0, 0.5, 2.3], [5.0, 0.5, 2.3])
    kin = jaw_kinematics(V, hinge, upper_teeth, lower_teeth, 10.0)[:3]
    theta = np.radians(kin[0])
    neck_band, back_band = (round(float(1.5 * theta * r), 1) for r in (ICT_NECK_R, ICT_BACK_R))
    mouth = [V[lm["mouth_corner_right"]],
             0.5 * (V[5711] + V[5966]), 0.5 * (V[lm["upper_lip_inner"]] + V[lm["lower_lip_inner"]]),
             0.5 * (V[6216] + V[6470]), V[lm["mouth_corner_left"]]]
    falloff = {"mouth_line": [r3(p) for p in mouth], "lip_band": 0.05, "cheek_band": ICT_CHEEK_BAND,
               "cheek_distance": ICT_CHEEK_DISTANCE, "corner_inset": ICT_CORNER_INSET,
               "inner_depth": ICT_INNER_DEPTH, "menton": [0.0, -8.0, 9.2], "gonion": [5.3, -5.0, 1.6],
               "neck_band": neck_band, "back_band": back_band}
    bone = [("cranium", "skull", cranium), ("ears", "skull", ears), ("upper_teeth", "skull", upper_teeth),
            ("eyeballs", "skull", eyeballs), ("lower_teeth", "jaw", lower_teeth)]
    first = rig("ict-facekit", "", mesh, V, 10.0, bone, lm, hinge, kin, falloff, ICT_RAMP)
    w, exact = ict_jaw_weights(V, F, first, lm)
    # gums and lining that the teeth fix at 0 or 1 are rigid with the skull or the jaw
    rigid = lambda part, v: part[exact[part] & (w[part] == v)]
    regions = bone[:4] + [
        ("upper_gums", "skull", rigid(gums, 0)), ("palate", "skull", rigid(socket, 0)),
        bone[4], ("lower_gums", "jaw", rigid(gums, 1)), ("mouth_floor", "jaw", rigid(socket, 1)),
        ("face", "soft", np.arange(0, 9409)), ("head_neck", "soft", np.arange(9409, 11248)),
        ("mouth_lining", "soft", socket), ("tongue_gums", "soft", gums),
        ("eye_sockets", "soft", np.arange(13294, 14062)),
        ("eye_surfaces", "soft", np.arange(24591, 25351)), ("eyelashes", "soft", np.arange(25351, 26719)),
    ]
    r = rig("ict-facekit", "ICT FaceKit generic neutral head (cm): skull, jaw, falloff from anatomy, "
            "jaw weights of the lips and the mouth's inside", mesh, V, 10.0, regions, lm, hinge,
            kin, falloff, ICT_RAMP)
    # the weights that differ from the falloff, soft vertices only, 4 decimals
    w_fall = falloff_weights(r, V)
    kind = np.zeros(len(V), int)
    for g in r["regions"]:
        kind[expand(g["vertices"])] = {"soft": 0, "skull": 1, "jaw": 2}[g["kind"]]
    listed = np.where((kind == 0) & (np.abs(w - w_fall) > 5e-5))[0]
    r["jaw"]["weights"] = {"vertices": ranges(listed), "values": [round(float(x), 4) for x in w[listed]]}
    return r, V, F


def ict_kin(ict_rig, scale=1.0):
    """The ICT jaw's (open_degrees, glide, glide_start), the glide scaled to another mesh."""
    j = ict_rig["jaw"]
    return j["open_degrees"], [round(g * scale, 4) for g in j["glide"]], j["glide_start"]


def build_mediapipe(data, ict_rig):
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
               mesh, V, 10.0, regions, lm, hinge, ict_kin(ict_rig), falloff, ICT_RAMP), V, F


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
               mesh, V, round(mm, 4), regions, lm, (T(h["right"]), T(h["left"])), ict_kin(ict_rig, s), fo,
               round(ICT_RAMP * s, 4)), V, F


def main():
    data = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / '../shared/data')
    out = Path(__file__).resolve().parents[1]
    ict, Vi, _ = build_ict(data)
    write(out / 'ict-facekit.json', ict)
    write(out / 'mediapipe-canonical.json', build_mediapipe(data, ict)[0])
    write(out / 'lee-perry-smith.json', build_lps(data, ict, Vi)[0])


if __name__ == '__main__':
    main()
