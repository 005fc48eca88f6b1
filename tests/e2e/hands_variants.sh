# hands_variants.sh: sourced by the e2e scripts that run the checks on transformed copies of
# the Leap recordings (tools/hands-variants): test_left_handed.sh, test_slow_tracker.sh.
#   variants_setup BUILD_DIR NAME   sets build, data and tmp (removed at exit), writes every
#                                   variant under $tmp; exits 77 (skipped) without python3
#                                   or the data, 1 when hands-variants fails
#   variant_guard_and_reach VARIANT WHAT
#                                   test_guard's recordings, anchored (where it is built:
#                                   CGAL), then test_reach on the three faces, on $tmp/VARIANT
#                                   (a folder: every *_joints_mm.csv in it, grab among them;
#                                   or one *_joints_mm.csv); exits 1 naming WHAT when either
#                                   fails
#   variant_onehand VARIANT WHAT    onehand on its defaults, $tmp/VARIANT's grab on each face
#                                   (its rig): it engages, moves the face and gives no hint
#                                   (a hand that reaches); exits 1 naming WHAT otherwise
# SPDX-License-Identifier: GPL-3.0-or-later

variants_setup() {
    build=${1:?usage: BUILD_DIR}
    data=${FP_SHARED_DATA:-../shared/data}
    [ -d "$data/hands/leap-motion" ] || { echo "no $data/hands/leap-motion: skipped"; exit 77; }
    command -v python3 >/dev/null || { echo "no python3: skipped"; exit 77; }
    tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-$2-XXXXXX")
    trap 'rm -rf "$tmp"' EXIT
    python3 tools/hands-variants "$tmp" --data "$data" || { echo "FAIL: hands-variants"; exit 1; }
}

variant_guard_and_reach() {
    [ -s "$tmp/$1" ] || [ -s "$tmp/$1/grab_joints_mm.csv" ] || { echo "FAIL: no grab in $tmp/$1"; exit 1; }
    if [ -x "$build/tests/test_guard" ]; then
        FP_SHARED_DATA=$data FP_GUARD_HANDS=$tmp/$1 FP_TEST_FILTER=test_recordings_anchored \
            "$build/tests/test_guard" || { echo "FAIL: test_guard on $2"; exit 1; }
    else
        echo "no test_guard (built where CGAL is): its part skipped"
    fi
    FP_SHARED_DATA=$data FP_REACH_HANDS=$tmp/$1 "$build/tests/test_reach" ||
        { echo "FAIL: test_reach on $2"; exit 1; }
}

variant_onehand() {
    local face line engaged moved max
    for face in ict-facekit/generic_neutral_mesh.obj lee-perry-smith/LeePerrySmith.obj \
                mediapipe-canonical/canonical_face_model.obj; do
        "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" --mesh "$data/faces/$face" \
            --mapping onehand --input "replay:$tmp/$1/grab_joints_mm.csv,fast=1" \
            --out "$tmp/onehand.obj" --force >"$tmp/onehand.out" 2>"$tmp/onehand.err" ||
            { cat "$tmp/onehand.err"; echo "FAIL: onehand run on $face"; exit 1; }
        line=$(grep '^frames' "$tmp/onehand.out")
        echo "onehand, $2, $face: $line"
        engaged=$(sed -n 's/.* engaged \([0-9]*\),.*/\1/p' <<<"$line")
        moved=$(sed -n 's/.*vertices moved \([0-9]*\) of.*/\1/p' <<<"$line")
        max=$(sed -n 's/.*displacement mean [^;]* max \([0-9.e+-]*\) mm.*/\1/p' <<<"$line")
        [ "${engaged:-0}" -ge 1 ] && [ "${moved:-0}" -gt 0 ] && awk -v m="${max:-0}" 'BEGIN { exit !(m > 0) }' ||
            { echo "FAIL: onehand on its defaults moved nothing under $2: $face"; exit 1; }
        ! grep -q "no fingertip came within" "$tmp/onehand.err" ||
            { cat "$tmp/onehand.err"; echo "FAIL: a hint for $2, which reaches: $face"; exit 1; }
    done
}
