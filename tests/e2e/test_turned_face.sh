#!/bin/bash
# A face exported in another frame (fp_rig_placement, fp_calibration.face): the ICT face in
# metres and moved, in Blender's Z-up (up +z, looking along -y) and turned 34 degrees about its
# up axis, each found its rig by the vertex count and placed by the rig's landmarks:
#  1. run says where it placed the rig; the grab recording, anchored, moves the copy as it
#     moves the face itself: vertices moved and the largest displacement in mm within 5%
#     (measured: equal in metres and Z-up, 12,605 against 12,659 vertices and 21.7 against
#     21.3 mm turned; before, metres refused the rig, exit 65, and Z-up moved 3 vertices);
#  2. without a rig, --up +z --facing -y on the Z-up copy gives what the face gives with
#     --rig none (within 5%; measured equal: 24,301 vertices, 77.5 mm), the unit detected in
#     the face's frame; --up alone, two parallel axes or an unknown axis: exit 64;
#  2a. without a rig nor axes, the Z-up copy draws a hint naming -y and the options (the face
#     itself none);
#  2c. a mirrored copy is said to be the rig's mesh mirrored (no similarity places the rig);
#  2b. pose opens the copy's jaw as it opens the face's (exit 0; the pose carried within
#     0.001 mm is test_rig's test_placement);
#  3. calibrate --mode hold on the Z-up copy (in metres) writes the face's calibration turned
#     and scaled with it (rotation 90 degrees about x, offset 0.01 (x, -z, y) of the face's,
#     within 0.01 mm; 1000 mm per unit), with its rig or with --rig none --up +z --facing -y;
#  4. export --format png-seq (under Xvfb, where the viewer is built) shows the Z-up copy from
#     the face's front, as it shows the face itself: the pictures of the same frame of the two
#     takes differ by under 2 of 255 a pixel on average (before: seen from above the crown);
#     so does a take with --rig none --up +z --facing -y (the take's header key face, 1.4).
# Usage: test_turned_face.sh BUILD_DIR. Exit 77 (skipped) without python3 or the data.
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${1:?usage: test_turned_face.sh BUILD_DIR}
data=${FP_SHARED_DATA:-../shared/data}
face=$data/faces/ict-facekit/generic_neutral_mesh.obj
grab=$data/hands/leap-motion/grab_joints_mm.csv
[ -s "$face" ] && [ -s "$grab" ] || { echo "no $face or $grab: skipped"; exit 77; }
command -v python3 >/dev/null || { echo "no python3: skipped"; exit 77; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-turned-XXXXXX")
trap 'rm -rf "$tmp"' EXIT

# the copies: every vertex position moved, every other line as it was
python3 - "$face" "$tmp" <<'EOF' || { echo "FAIL: writing the copies"; exit 1; }
import math, sys
src, out = sys.argv[1], sys.argv[2]
lines = open(src).read().split('\n')
c, s = math.cos(0.6), math.sin(0.6)
copies = {
    'metres': lambda x, y, z: (0.01 * x + 0.3, 0.01 * y - 1.2, 0.01 * z + 0.05),
    'zup': lambda x, y, z: (0.01 * x, -0.01 * z, 0.01 * y),
    'turned': lambda x, y, z: (c * x + s * z, y, -s * x + c * z),
    'mirrored': lambda x, y, z: (-0.01 * x, 0.01 * y, 0.01 * z),
}
for name, f in copies.items():
    with open(f'{out}/{name}.obj', 'w') as o:
        for l in lines:
            if l.startswith('v '):
                p = l.split()
                o.write('v %.7g %.7g %.7g\n' % f(*map(float, p[1:4])))
            elif not l.startswith('vn '):
                o.write(l + '\n')
EOF

summary() { # MESH NAME: run's summary line into $tmp/NAME.out, its lines into $tmp/NAME.err
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$1" \
        --input "replay:$grab,fast=1" --out "$tmp/$2.out.obj" --force >"$tmp/$2.out" 2>"$tmp/$2.err" ||
        { cat "$tmp/$2.err"; echo "FAIL: run on $2"; exit 1; }
}
field() { # NAME WHAT: vertices moved (moved) or the largest displacement in mm (max)
    case $2 in
    moved) sed -n 's/.*vertices moved \([0-9]*\) of.*/\1/p' "$tmp/$1.out" "$tmp/$1.err" | head -1 ;;
    max) sed -n 's/.*displacement mean [0-9.e+-]* mm max \([0-9.e+-]*\) mm.*/\1/p' "$tmp/$1.out" "$tmp/$1.err" | head -1 ;;
    esac
}

summary "$face" face
m0=$(field face moved)
x0=$(field face max)
[ -n "$m0" ] && [ -n "$x0" ] || { cat "$tmp/face.out" "$tmp/face.err"; echo "FAIL: no summary on the face"; exit 1; }
for name in metres zup turned; do
    summary "$tmp/$name.obj" "$name"
    grep -q "placed on this mesh by its landmarks" "$tmp/$name.out" "$tmp/$name.err" ||
        { cat "$tmp/$name.err"; echo "FAIL: $name: the rig not placed"; exit 1; }
    m=$(field "$name" moved)
    x=$(field "$name" max)
    echo "$name: $m vertices moved, max $x mm (the face itself: $m0, $x0 mm)"
    python3 -c "import sys; a, b, c, d = map(float, sys.argv[1:]); sys.exit(not (abs(a / b - 1) <= 0.05 and abs(c / d - 1) <= 0.05))" \
        "$m" "$m0" "$x" "$x0" || { echo "FAIL: $name moves otherwise than the face"; exit 1; }
done

# without a rig nor --up/--facing, the Z-up copy draws the hint (its vertices lie toward -y,
# where its face looks); the face itself does not
for name in zup face; do
    mesh=$tmp/$name.obj
    [ "$name" = face ] && mesh=$face
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$mesh" --rig none -q \
        --input "replay:$grab,fast=1" --duration 0.1 --out "$tmp/hint.obj" --force >/dev/null 2>"$tmp/hint.err" ||
        { cat "$tmp/hint.err"; echo "FAIL: run on $name --rig none"; exit 1; }
    if [ "$name" = zup ]; then
        grep -q "its vertices lie most toward -y.*--up +z --facing -y" "$tmp/hint.err" ||
            { cat "$tmp/hint.err"; echo "FAIL: no facing hint on the Z-up copy without a rig"; exit 1; }
    elif grep -q "no rig and no --up/--facing" "$tmp/hint.err"; then
        cat "$tmp/hint.err"; echo "FAIL: a facing hint on the face itself"; exit 1
    fi
done
echo "the Z-up copy without a rig: the hint to give --up +z --facing -y; the face itself: none"

# 2c. a mirrored copy (left for right, in metres) has the rig's vertex count but no turn, scale
# or move places the rig on it: run says it is the mesh mirrored (it said "another face, or its
# own with the vertices in another order") and runs without the rig
"$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$tmp/mirrored.obj" \
    --input "replay:$grab,fast=1" --duration 0.1 --out "$tmp/mirrored.out.obj" --force >/dev/null 2>"$tmp/mirrored.err" ||
    { cat "$tmp/mirrored.err"; echo "FAIL: run on the mirrored copy"; exit 1; }
grep -q "rig none (.*is its mesh mirrored, left for right.*mirror the face back" "$tmp/mirrored.err" ||
    { cat "$tmp/mirrored.err"; echo "FAIL: the mirrored copy not said to be mirrored"; exit 1; }
echo "the mirrored copy: said to be its rig's mesh mirrored, run without the rig"

# a smooth head (an ellipsoid 15 x 23 x 19 units with a nose 2.4 units out and a mouth slit),
# its vertices spread evenly: the mean says nothing, the hint above never fired on its Z-up
# copy (unit and placement taken along the wrong axes, 6,101 vertices moved against 7,618);
# its nose does (fp_head_nose): the Z-up copy and one looking along +x draw the hint with the
# options, the head itself none
smooth_head() { # FILE UP FACING: the head with +y turned into UP and +z into FACING
    python3 - "$@" <<'PY'
import math, sys
out, up, fa = sys.argv[1:4]
ax = lambda s: [(1 if s[0] == "+" else -1) if "xyz".index(s[1]) == i else 0 for i in range(3)]
u, f = ax(up), ax(fa)
l = [u[1] * f[2] - u[2] * f[1], u[2] * f[0] - u[0] * f[2], u[0] * f[1] - u[1] * f[0]]
LAT, LON = 60, 90
with open(out, "w") as o:
    for i in range(LAT + 1):
        for j in range(LON):
            th, ph = math.pi * i / LAT, 2 * math.pi * j / LON
            d = (math.sin(th) * math.sin(ph), math.cos(th), math.sin(th) * math.cos(ph))
            nose = math.exp(-((d[0] / 0.12) ** 2 + ((d[1] + 0.05) / 0.2) ** 2)) * max(d[2], 0)
            mouth = math.exp(-((d[1] + 0.45) / 0.03) ** 2) * math.exp(-((d[0] / 0.3) ** 4)) * max(d[2], 0)
            p = [a * c * (1 + 0.25 * nose - 0.06 * mouth) for a, c in zip((7.5, 11.5, 9.5), d)]
            o.write("v %.5f %.5f %.5f\n" % tuple(p[0] * l[k] + p[1] * u[k] + p[2] * f[k] for k in range(3)))
    for i in range(LAT):
        for j in range(LON):
            a, b = i * LON + j + 1, i * LON + (j + 1) % LON + 1
            o.write("f %d %d %d\nf %d %d %d\n" % (a, a + LON, b, b, a + LON, b + LON))
PY
}
for case in "+y +z none" "+z -y -y" "+z +x +x"; do
    set -- $case
    smooth_head "$tmp/smooth.obj" "$1" "$2" || { echo "FAIL: cannot write the smooth head"; exit 1; }
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$tmp/smooth.obj" --rig none -q \
        --input "replay:$grab,fast=1" --duration 0.1 --out "$tmp/hint.obj" --force >/dev/null 2>"$tmp/hint.err" ||
        { cat "$tmp/hint.err"; echo "FAIL: run on the smooth head, up $1 facing $2"; exit 1; }
    if [ "$3" = none ]; then
        ! grep -q "no rig and no --up/--facing" "$tmp/hint.err" ||
            { cat "$tmp/hint.err"; echo "FAIL: a facing hint on the smooth head itself"; exit 1; }
    else
        grep -q "a nose, points along $3.*--up +z --facing $3" "$tmp/hint.err" ||
            { cat "$tmp/hint.err"; echo "FAIL: no nose hint on the smooth head looking along $3, up $1"; exit 1; }
    fi
done
echo "the smooth head: the nose's hint looking along -y and +x with up +z; looking along +z none"

png() { # MESH NAME [OPTIONS...]: frame 100 of a take of the grab on MESH, rendered into $tmp/NAME.png.d
    local mesh=$1 name=$2
    shift 2
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$mesh" "$@" \
        --input "replay:$grab,fast=1" --take-dir "$tmp/$name.takes" --out "$tmp/$name.t.obj" --force \
        >/dev/null 2>&1 || { echo "FAIL: the take on $name"; exit 1; }
    # (Mesa's allocations for the process's life unwind to no module: no leak check of the
    # drawing in a sanitizer build, as FP_GL_ASAN_ENV does for the drawing tests)
    ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0" LIBGL_ALWAYS_SOFTWARE=1 \
        xvfb-run -a -s "-screen 0 1280x720x24" "$build/bin/facepuppet" export \
        "$(ls "$tmp/$name.takes"/*.fptake | head -1)" --format png-seq --range 100-100 --size 320x240 \
        --out "$tmp/$name.png.d" -q >/dev/null 2>&1 || { echo "FAIL: png-seq of $name"; exit 1; }
}
if "$build/bin/facepuppet" live --help >/dev/null 2>&1 && command -v xvfb-run >/dev/null; then
    png "$face" face
    png "$tmp/zup.obj" zup
    png "$face" face_norig --rig none
    png "$tmp/zup.obj" zup_norig --rig none --up +z --facing -y
    for pair in "face zup" "face_norig zup_norig"; do
    set -- $pair
    PYTHONPATH="$(dirname "$0")/../support" python3 - "$(ls "$tmp/$1.png.d"/*.png)" "$(ls "$tmp/$2.png.d"/*.png)" <<'EOF' ||
import sys
from pngread import read_png
def pixels(path):  # the RGB bytes, alpha left out
    w, h, bpp, rows = read_png(path)
    return b''.join(bytes(v for k, v in enumerate(row) if k % bpp < 3) for row in rows)
a, b = pixels(sys.argv[1]), pixels(sys.argv[2])
diff = sum(abs(x - y) for x, y in zip(a, b)) / len(a)
print(f"png-seq: {sys.argv[2].split('/')[-2]}'s frame 100 differs from the face's by {diff:.2f} of 255 a pixel")
assert len(set(a)) > 20 and diff < 2, diff
EOF
        { echo "FAIL: the Z-up copy ($2) is not seen as the face is"; exit 1; }
    done
else
    echo "SKIP (png-seq only): no viewer in this build or no xvfb-run"
fi

summary_norig() { # MESH NAME [OPTIONS...]
    local mesh=$1 name=$2
    shift 2
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$mesh" --rig none "$@" \
        --input "replay:$grab,fast=1" --out "$tmp/$name.out.obj" --force >"$tmp/$name.out" 2>"$tmp/$name.err" ||
        { cat "$tmp/$name.err"; echo "FAIL: run on $name"; exit 1; }
}
summary_norig "$face" face_norig
summary_norig "$tmp/zup.obj" zup_norig --up +z --facing -y
m0=$(field face_norig moved); x0=$(field face_norig max); m=$(field zup_norig moved); x=$(field zup_norig max)
echo "no rig: the Z-up copy with --up +z --facing -y: $m vertices moved, max $x mm (the face: $m0, $x0 mm)"
python3 -c "import sys; a, b, c, d = map(float, sys.argv[1:]); sys.exit(not (abs(a / b - 1) <= 0.05 and abs(c / d - 1) <= 0.05))" \
    "$m" "$m0" "$x" "$x0" || { echo "FAIL: the Z-up copy with --up and --facing moves otherwise than the face"; exit 1; }
for bad in "--up +z" "--up +z --facing +z" "--up w --facing -y"; do
    # shellcheck disable=SC2086
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$tmp/zup.obj" --rig none $bad \
        --input "replay:$grab" --out "$tmp/bad.obj" --force >/dev/null 2>"$tmp/bad.err"
    rc=$?
    [ $rc -eq 64 ] || { cat "$tmp/bad.err"; echo "FAIL: '$bad' exited $rc, want 64"; exit 1; }
done

for name in face zup face_norig zup_norig; do
    mesh=$face
    opts=()
    case $name in zup*) mesh=$tmp/zup.obj ;; esac
    case $name in face_norig) opts=(--rig none) ;; zup_norig) opts=(--rig none --up +z --facing -y) ;; esac
    "$build/bin/facepuppet" calibrate --mesh "$mesh" "${opts[@]}" --input "replay:$data/hands/leap-motion/Waiting-110fps_joints_mm.csv" \
        --out "$tmp/$name.cal.json" >"$tmp/cal.out" 2>&1 || { cat "$tmp/cal.out"; echo "FAIL: calibrate on $name"; exit 1; }
done
for pair in "face zup" "face_norig zup_norig"; do
set -- $pair
python3 - "$tmp/$1.cal.json" "$tmp/$2.cal.json" <<'EOF' || { echo "FAIL: the Z-up copy's calibration ($2) is not the face's turned"; exit 1; }
import json, math, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
(ax, ay, az), (bx, by, bz) = a["offset"], b["offset"]
q, h = b["rotation"], math.sqrt(0.5)
print("calibrate: offset", [round(v, 3) for v in b["offset"]], "rotation", [round(v, 4) for v in q])
s = 0.01  # (the copy is in metres)
assert max(abs(bx - s * ax), abs(by + s * az), abs(bz - s * ay)) < 1e-5, (a, b)
assert abs(b["mm_per_unit"] / a["mm_per_unit"] / 100 - 1) < 1e-4, (a, b)
assert abs(q[0] - h) < 1e-4 and abs(q[1] - h) < 1e-4 and abs(q[2]) < 1e-4 and abs(q[3]) < 1e-4, q
EOF
done

for name in metres zup; do
    "$build/bin/facepuppet" pose --mesh "$tmp/$name.obj" --set jaw.open=0.6 --out "$tmp/$name.posed.obj" \
        >"$tmp/pose.out" 2>&1 || { cat "$tmp/pose.out"; echo "FAIL: pose on $name"; exit 1; }
done
echo ok
