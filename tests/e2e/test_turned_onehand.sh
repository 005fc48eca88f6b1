#!/bin/bash
# onehand on a turned copy of a rigged face moves it as it moves the face itself: the ICT face
# in Blender's Z-up (up +z, looking along -y) and looking along -z (turned 180 degrees about
# +y), copies made here by exact float swaps and negations, each found its rig by the vertex
# count and placed by its landmarks (fp_rig_placement), the hands placed in front of the face
# and turned with it (fp_calibration.face). HandSplay through `--mapping onehand`: every vertex
# of the copy's result, turned back, within 0.01 mm of the face's own result (measured 0.00016
# mm; before, the mapping took the turned hands' motion as +x, +y, +z and turned it again with
# the rig's axes: a hand moving up pulled the Z-up copy's landmarks toward the viewer, 12.6 mm
# off, and the -z copy's 25.4 mm off).
# Usage: test_turned_onehand.sh BUILD_DIR. Exit 77 (skipped) without python3 or the data.
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${1:?usage: test_turned_onehand.sh BUILD_DIR}
data=${FP_SHARED_DATA:-../shared/data}
face=$data/faces/ict-facekit/generic_neutral_mesh.obj
rec=$data/hands/leap-motion/HandSplay-110fps_joints_mm.csv
[ -s "$face" ] && [ -s "$rec" ] || { echo "no $face or $rec: skipped"; exit 77; }
command -v python3 >/dev/null || { echo "no python3: skipped"; exit 77; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-turned-onehand-XXXXXX")
trap 'rm -rf "$tmp"' EXIT

# the copies: every vertex position turned exactly (a swap and a sign), every other line kept
python3 - "$face" "$tmp" <<'PY' || { echo "FAIL: writing the copies"; exit 1; }
import sys
src, out = sys.argv[1], sys.argv[2]
lines = open(src).read().split('\n')
copies = {'zup': lambda x, y, z: (x, '-' + z, y), 'negz': lambda x, y, z: ('-' + x, y, '-' + z)}
for name, f in copies.items():
    with open(f'{out}/{name}.obj', 'w') as o:
        for l in lines:
            if l.startswith('v '):
                p = l.split()
                o.write('v %s %s %s\n' % tuple(c[2:] if c.startswith('--') else c for c in f(*p[1:4])))
            elif not l.startswith('vn '):
                o.write(l + '\n')
PY

for name in face zup negz; do
    mesh=$tmp/$name.obj
    [ "$name" = face ] && mesh=$face
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$mesh" --mapping onehand \
        --input "replay:$rec,fast=1" --out "$tmp/$name.out.obj" >"$tmp/$name.log" 2>&1 ||
        { cat "$tmp/$name.log"; echo "FAIL: run on $name"; exit 1; }
    [ "$name" = face ] || grep -q "placed on this mesh by its landmarks" "$tmp/$name.log" ||
        { cat "$tmp/$name.log"; echo "FAIL: $name: the rig not placed"; exit 1; }
done

python3 - "$tmp" <<'PY'
import math, sys
t = sys.argv[1]
def rd(p): return [tuple(map(float, l.split()[1:4])) for l in open(p) if l.startswith('v ')]
face = rd(f'{t}/face.out.obj')
back = {'zup': lambda p: (p[0], p[2], -p[1]), 'negz': lambda p: (-p[0], p[1], -p[2])}
bad = False
for name, f in back.items():
    got = rd(f'{t}/{name}.out.obj')
    worst = max(math.dist(a, f(b)) for a, b in zip(face, got)) * 10.0  # ICT: 10 mm per unit
    print(f'{name}: every vertex within {worst:.3g} mm of the face\'s own result')
    if len(got) != len(face) or not worst <= 0.01:
        print(f'FAIL: onehand moves the {name} copy otherwise than the face'); bad = True
sys.exit(1 if bad else 0)
PY
