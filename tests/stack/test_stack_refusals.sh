#!/bin/bash
# Stacks: what `run --over` and `play STACK` refuse, and that each refusal names the right
# files (an outside audit's findings; docs/stack.md, "Exit status"):
#  1. run --over a take of one face with --mesh another face: exit 65, and the message names
#     the mesh loaded (--mesh) and the take's own mesh, each with its vertex count (before:
#     the take's mesh path twice, beside the loaded mesh's count and checksum).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
pd=(--plugin-dir "$build/lib/facepuppet")
data=${FP_SHARED_DATA:-../shared/data}
ict=$data/faces/ict-facekit/generic_neutral_mesh.obj
lee=$data/faces/lee-perry-smith/LeePerrySmith.obj
grab=$data/hands/leap-motion/grab_joints_mm.csv
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-stack-refusals-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
takes="$tmp/takes"

# ---- 1. a pass on another face over a take ------------------------------------------------
"$fp" run "${pd[@]}" --mesh "$ict" --input "replay:$grab,fast=1" --duration 0.5 --take-dir "$takes" \
    --slate base -o "$tmp/base.obj" -q 2>"$tmp/base.err" || { cat "$tmp/base.err"; fail "base run exited $?"; }
"$fp" run "${pd[@]}" --mesh "$lee" --input "replay:$grab,fast=1" --duration 0.5 --take-dir "$takes" \
    --slate pass --over "$takes/base_T001.fptake" --layer mouth -o "$tmp/pass.obj" -q 2>"$tmp/pass.err"
rc=$?
cat "$tmp/pass.err"
[ $rc -eq 65 ] || fail "run --over on another mesh exited $rc, want 65"
nl=$(grep -c . "$tmp/pass.err")
[ "$nl" -eq 1 ] || fail "want one line, got $nl"
grep -qF "facepuppet run: --over: $takes/base_T001.fptake: mesh $lee (8838 vertices, " "$tmp/pass.err" ||
    fail "the message does not name the loaded mesh ($lee) with its vertex count"
grep -qF "is not the take's mesh $ict (26719 vertices, " "$tmp/pass.err" ||
    fail "the message does not name the take's mesh ($ict)"
[ ! -e "$takes/pass_T001.fptake" ] && ! ls "$takes"/*.fpstack >/dev/null 2>&1 ||
    fail "a take or stack was written after the refusal"
echo "PASS: run --over on another face refused, naming both meshes"
