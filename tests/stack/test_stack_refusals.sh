#!/bin/bash
# Stacks: what `run --over` and `play STACK` refuse, and that each refusal names the right
# files (an outside audit's findings; docs/stack.md, "Exit status"):
#  1. run --over a take of one face with --mesh another face: exit 65, and the message names
#     the mesh loaded (--mesh) and the take's own mesh, each with its vertex count (before:
#     the take's mesh path twice, beside the loaded mesh's count and checksum).
#  2. run --over with a --punch that starts after the pass's last frame: the stack is written
#     as asked, with a warning that the new layer changes nothing (before: silent); a punch
#     inside the pass: no warning.
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

# ---- 2. a punch past the pass's end ----------------------------------------------------------
for punch in 3.7:100 0.1:0.3; do
    "$fp" run "${pd[@]}" --mesh "$ict" --input "replay:$grab,fast=1" --duration 0.5 --take-dir "$takes" \
        --slate late --over "$takes/base_T001.fptake" --layer mouth --punch $punch -o "$tmp/late-$punch.obj" \
        -q 2>"$tmp/late.err" || { cat "$tmp/late.err"; fail "run --punch $punch exited $?"; }
    cat "$tmp/late.err"
    grep -q "stack .*late_S00[12].fpstack" "$tmp/late.err" || fail "--punch $punch: no stack written"
    if [ $punch = 3.7:100 ]; then
        grep -qE "warning: --punch 3.7:100 starts after the pass's last frame \(0\.[0-9]+ s\): the new layer changes nothing" \
            "$tmp/late.err" || fail "--punch 3.7:100 past a 0.5 s pass: no warning"
    else
        ! grep -q "warning: --punch" "$tmp/late.err" || fail "--punch 0.1:0.3 inside the pass warned"
    fi
done
echo "PASS: a punch past the pass's end is said"
