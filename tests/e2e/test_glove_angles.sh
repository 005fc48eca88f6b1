#!/bin/bash
# Any Leap recording through the glove path (joint angles, forward kinematics, gloves placed on
# the face): tools/joints-to-angles makes the angles the shipped *_cyberglove_like_angles_deg.csv
# hold, from joints.
#  1. --check: the four shipped recordings' angles from their joints, every column within
#     0.05 degrees of the shipped files (measured: 0.010 at most; the joints CSVs hold 4
#     decimals);
#  2. hands the project has no angles for: tools/hands-variants' stillpinch (each recording's
#     middle pose held, thumb and index pinching every 1.5 s) made into angles, replayed on
#     the ICT face with onehand on its defaults: it engages and moves the face, no hint.
# Usage: test_glove_angles.sh BUILD_DIR. Exit 77 (skipped) without python3 or the data.
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${1:?usage: test_glove_angles.sh BUILD_DIR}
data=${FP_SHARED_DATA:-../shared/data}
command -v python3 >/dev/null || { echo "skipped: no python3"; exit 77; }
[ -f "$data/hands/leap-motion/grab_joints_mm.csv" ] || { echo "skipped: no $data"; exit 77; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-glove-angles-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

python3 tools/joints-to-angles --check --data "$data" || fail "joints-to-angles does not give the shipped angles"
python3 tools/hands-variants "$tmp/v" --data "$data" >/dev/null || fail "hands-variants"
for rec in grab three-claps; do
    python3 tools/joints-to-angles "$tmp/v/stillpinch/${rec}_joints_mm.csv" "$tmp/${rec}_angles.csv" ||
        fail "joints-to-angles on $rec"
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" \
        --mesh "$data/faces/ict-facekit/generic_neutral_mesh.obj" --input "replay:$tmp/${rec}_angles.csv,fast=1" \
        --mapping onehand --out "$tmp/$rec.obj" >"$tmp/$rec.out" 2>"$tmp/$rec.err" ||
        { cat "$tmp/$rec.err"; fail "run on $rec's pinching angles exited $?"; }
    moved=$(sed -n 's/.*engaged \([0-9]*\), committed [0-9]*; vertices moved \([0-9]*\) of.*/\1 \2/p' "$tmp/$rec.out")
    echo "$rec, still and pinching, as glove angles, onehand on ICT: engaged, moved: $moved"
    read -r e m <<<"$moved"
    [ "${e:-0}" -ge 1 ] && [ "${m:-0}" -gt 0 ] || { cat "$tmp/$rec.out"; fail "onehand on $rec's pinching angles moved nothing"; }
    ! grep -q "no fingertip came within" "$tmp/$rec.err" || fail "a hint for gloves on the face"
done
echo ok
