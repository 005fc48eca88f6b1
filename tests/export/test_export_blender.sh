#!/usr/bin/env bash
# Exports that land right in Blender (issue 53): a 60 fps take of the ICT face (recorded by
# `run --take-dir` from the Leap HandSplay recording), exported to glb, pc2 and mdd, then
# Debian's Blender, headless (blender -b --factory-startup), runs tests/export/blender_check.py:
#  - the glb imports at life size: the face (head and neck, 33.8 mesh units of 10 mm) is
#    0.338 m tall in world space (within 3%; without the root scale it would be 33.8 m), the
#    file names its rate and the keys span the take's duration at the scene's rate;
#  - the README's recipe (its "blender-recipe" block, executed as written) plays the PC2 at
#    60 fps: the scene runs at 60 fps over the take's frames, and scene frame 1 + k shows the
#    take's frame k exactly at frames where the face moves (not k - 1, not k + 1);
#  - the MDD by its own times in a 24 fps scene (the README's Time Mode block).
#  - a take at 29.97 fps (30000/1001) on a glTF face (the MediaPipe face as a GLB): the
#    README's glTF-face recipe (the face from its GLB, the cache turned from Y-up) shows scene
#    frame 1 + k as the take's frame k in metres, Z-up; and its glb in a 29.97 scene with the
#    README's block that moves the keys (Blender 3.4 keys at t x 30) within --max-error.
# The caches are the take's frames bit for bit (fp-export-check) and the summary lines name
# the scale and the rate. Skipped (exit 77) only where blender is not installed.
set -uo pipefail
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
check="$build/tests/fp-export-check"
pd=(--plugin-dir "$build/lib/facepuppet")
data=${FP_SHARED_DATA:-../shared/data}
fail() { echo "FAIL: $*"; exit 1; }

if ! command -v blender >/dev/null; then
    echo "SKIP: blender is not installed (Debian: apt-get install blender; tools/fp-setup installs it)"
    exit 77
fi
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-blender-XXXXXX")
trap 'rm -rf "$tmp"' EXIT

face="$data/faces/ict-facekit/generic_neutral_mesh.obj"
"$fp" run "${pd[@]}" --mesh "$face" \
    --input "replay:$data/hands/leap-motion/HandSplay-110fps_joints_mm.csv,fast=1" \
    --duration 4 --take-dir "$tmp/takes" --slate ict -o "$tmp/run.obj" -q \
    >"$tmp/run.out" 2>&1 || { cat "$tmp/run.out"; fail "run exited $?"; }
take=$(ls "$tmp"/takes/*.fptake)
for fmt in glb pc2 mdd; do
    "$fp" export "$take" --format $fmt --out "$tmp/take.$fmt" >"$tmp/export-$fmt.out" 2>&1 ||
        { cat "$tmp/export-$fmt.out"; fail "export $fmt exited $?"; }
    line=$(grep "exported" "$tmp/export-$fmt.out")
    echo "$line"
    # every summary names the rate; the glb its root scale, the caches the unit
    [[ $line == *"; 60 fps" ]] || fail "$fmt: the export's line does not end in '; 60 fps'"
    if [ $fmt = glb ]; then
        [[ $line == *"in metres: root node scale 0.01 (10 mm per mesh unit)"* ]] ||
            fail "glb: the line does not say 'in metres: root node scale 0.01 (10 mm per mesh unit)'"
    else
        [[ $line == *"mesh units of 10 mm (scale 0.01 for metres)"* ]] ||
            fail "$fmt: the line does not say 'mesh units of 10 mm (scale 0.01 for metres)'"
    fi
    "$check" "$take" "$tmp/take.$fmt" >"$tmp/check-$fmt.out" 2>&1 ||
        { cat "$tmp/check-$fmt.out"; fail "$fmt: fp-export-check"; }
done
frames=$(sed -n 's/.*exported \([0-9]*\) frames.*/\1/p' "$tmp/export-pc2.out")
[ -n "$frames" ] && [ "$frames" -gt 60 ] || fail "the take has '$frames' frames, want more than 60"

# a take on a glTF face at 29.97 fps (30000/1001): the MediaPipe face written as a GLB by `pose`
mpface="$tmp/mediapipe.glb"
"$fp" pose --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" --set jaw.open=0 \
    --out "$mpface" >"$tmp/pose.out" 2>&1 || { cat "$tmp/pose.out"; fail "pose exited $?"; }
"$fp" run "${pd[@]}" --mesh "$mpface" \
    --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1" --fps 29.97 \
    --duration 4 --take-dir "$tmp/mptakes" --slate mp -o "$tmp/mprun.glb" -q \
    >"$tmp/mprun.out" 2>&1 || { cat "$tmp/mprun.out"; fail "run (MediaPipe GLB) exited $?"; }
mptake=$(ls "$tmp"/mptakes/*.fptake)
for fmt in glb pc2; do
    "$fp" export "$mptake" --format $fmt --out "$tmp/mp.$fmt" >"$tmp/mpexport-$fmt.out" 2>&1 ||
        { cat "$tmp/mpexport-$fmt.out"; fail "export $fmt (MediaPipe GLB) exited $?"; }
    line=$(grep "exported" "$tmp/mpexport-$fmt.out")
    echo "$line"
    [[ $line == *"10 mm"*"; 29.97 fps" ]] || fail "$fmt (MediaPipe GLB): the line does not say 10 mm and 29.97 fps"
    "$check" "$mptake" "$tmp/mp.$fmt" >"$tmp/mpcheck-$fmt.out" 2>&1 ||
        { cat "$tmp/mpcheck-$fmt.out"; fail "$fmt (MediaPipe GLB): fp-export-check"; }
done
mpframes=$(sed -n 's/.*exported \([0-9]*\) frames.*/\1/p' "$tmp/mpexport-pc2.out")
[ -n "$mpframes" ] && [ "$mpframes" -gt 60 ] || fail "the MediaPipe take has '$mpframes' frames, want more than 60"

blender -b --factory-startup --python-exit-code 1 --python tests/export/blender_check.py -- \
    --readme README.md --glb "$tmp/take.glb" --obj "$face" --pc2 "$tmp/take.pc2" \
    --mdd "$tmp/take.mdd" --fps 60 --frames "$frames" --scale 0.01 --height 0.338 --tol 0.03 \
    --face "$mpface" --face-pc2 "$tmp/mp.pc2" --face-glb "$tmp/mp.glb" \
    --face-fps 30000/1001 --face-frames "$mpframes" --face-scale 0.01 \
    >"$tmp/blender.out" 2>&1
rc=$?
grep "^blender-check:" "$tmp/blender.out"
if [ $rc -ne 0 ] || ! grep -qx "blender-check: PASS" "$tmp/blender.out"; then
    tail -30 "$tmp/blender.out"
    fail "Blender's checks (exit $rc)"
fi
echo "PASS"
