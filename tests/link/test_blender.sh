#!/usr/bin/env bash
# The face streamed live into Blender (issue 55, item 3): a 4 s take of a real recording on the
# ICT face (run --take-dir, the three-claps recording looped: 241 frames), `facepuppet play --stream` at its
# pace into Debian's Blender, headless, where the add-on tools/blender/facepuppet_live.py
# receives it on the face imported from the same OBJ and records it as shape-key animation
# (tests/link/blender_live_check.py); every recorded frame, evaluated by Blender at its scene
# frame, matches the take's frames (its PC2, the frames `facepuppet play` makes) within
# 0.1 mm, one scene frame per take frame. Skipped (exit 77) only where blender is missing.
# SPDX-License-Identifier: GPL-3.0-or-later
set -uo pipefail
build=${FP_BUILD_DIR:-build}
data=${FP_SHARED_DATA:-../shared/data}
fp="$build/bin/facepuppet"
pd=(--plugin-dir "$build/lib/facepuppet")
fail() { echo "FAIL: $*"; exit 1; }
if ! command -v blender >/dev/null; then
    echo "SKIP: blender is not installed (Debian: apt-get install blender; tools/fp-setup installs it)"
    exit 77
fi
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-blender-live-XXXXXX")
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$tmp"' EXIT
face="$data/faces/ict-facekit/generic_neutral_mesh.obj"
"$fp" run "${pd[@]}" --mesh "$face" \
    --input "replay:$data/hands/leap-motion/three-claps_joints_mm.csv,fast=1,loop=1" \
    --duration 4 --take-dir "$tmp/takes" --slate live -o "$tmp/run.obj" -q >"$tmp/run.out" 2>&1 ||
    { cat "$tmp/run.out"; fail "run exited $?"; }
take=$(ls "$tmp"/takes/*.fptake)
# the frames `facepuppet play` makes, kept as a PC2 (--export; bit for bit the session's)
"$fp" play "${pd[@]}" "$take" --export "$tmp/take.pc2" >"$tmp/export.out" 2>&1 ||
    { cat "$tmp/export.out"; fail "play --export exited $?"; }
grep "exported" "$tmp/export.out"
frames=$(sed -n 's/.*exported \([0-9]*\) frames.*/\1/p' "$tmp/export.out")
[ -n "$frames" ] && [ "$frames" -ge 240 ] || fail "the take has '$frames' frames, want 4 s at 60 fps"
for attempt in 1 2 3 4 5; do
    port=$((20000 + RANDOM % 40000))
    blender -b --factory-startup --python-exit-code 1 --python tests/link/blender_live_check.py -- \
        --addon tools/blender/facepuppet_live.py --obj "$face" --pc2 "$tmp/take.pc2" --port $port \
        --tol-mm 0.1 >"$tmp/blender.out" 2>&1 &
    b=$!
    for i in $(seq 600); do
        grep -q "^blender-live: listening" "$tmp/blender.out" && break
        kill -0 $b 2>/dev/null || break
        sleep 0.1
    done
    if ! grep -q "^blender-live: listening" "$tmp/blender.out"; then
        wait $b
        grep -q "Address already in use" "$tmp/blender.out" && continue
        tail -20 "$tmp/blender.out"
        fail "Blender did not start listening"
    fi
    "$fp" play "${pd[@]}" "$take" -q --stream "osc:127.0.0.1:$port" >"$tmp/play.out" 2>&1 ||
        { cat "$tmp/play.out"; fail "play exited $?"; }
    grep -e "--stream: [0-9]" "$tmp/play.out"
    wait $b
    rc=$?
    grep "^blender-live:" "$tmp/blender.out"
    if [ $rc -ne 0 ] || ! grep -qx "blender-live: PASS" "$tmp/blender.out"; then
        tail -30 "$tmp/blender.out"
        fail "Blender's checks (exit $rc)"
    fi
    echo "PASS"
    exit 0
done
fail "no free port in 5 tries"
