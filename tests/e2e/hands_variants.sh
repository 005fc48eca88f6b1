# hands_variants.sh: sourced by the e2e scripts that run the checks on transformed copies of
# the Leap recordings (tools/hands-variants): test_left_handed.sh, test_slow_tracker.sh.
#   variants_setup BUILD_DIR NAME   sets build, data and tmp (removed at exit), writes every
#                                   variant under $tmp; exits 77 (skipped) without python3
#                                   or the data, 1 when hands-variants fails
#   variant_guard_and_reach VARIANT WHAT
#                                   test_guard's recordings, anchored (where it is built:
#                                   CGAL), then test_reach on the three faces, on $tmp/VARIANT;
#                                   exits 1 naming WHAT when either fails
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
    [ -s "$tmp/$1/grab_joints_mm.csv" ] || { echo "FAIL: no grab in $tmp/$1"; exit 1; }
    if [ -x "$build/tests/test_guard" ]; then
        FP_SHARED_DATA=$data FP_GUARD_HANDS=$tmp/$1 FP_TEST_FILTER=test_recordings_anchored \
            "$build/tests/test_guard" || { echo "FAIL: test_guard on $2"; exit 1; }
    else
        echo "no test_guard (built where CGAL is): its part skipped"
    fi
    FP_SHARED_DATA=$data FP_REACH_HANDS=$tmp/$1 "$build/tests/test_reach" ||
        { echo "FAIL: test_reach on $2"; exit 1; }
}
