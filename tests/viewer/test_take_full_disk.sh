#!/bin/sh
# A full disk mid-take in `live` (run under xvfb-run by ctest): the take's failed write is said
# at once and the take stopped (REC off), the session goes on, and the run's end fails with
# the take's message (exit 73). The disk fills through enospc_shim.so (tests/harden), an
# LD_PRELOAD that lets the take's file have FP_ENOSPC_AFTER bytes. Before, nothing was said
# until T or the window's close stopped the take (the REC went on while nothing was written),
# and the end's message was lost to the overdub's line ("viewer: the run failed").
# Usage: test_take_full_disk.sh FACEPUPPET SHIM   (from the source root)
set -u
fp=$1
shim=$2
data=${FP_SHARED_DATA:-../shared/data}
rec=$data/hands/leap-motion/three-claps_joints_mm.csv
scale=${FP_TEST_TIMEOUT_SCALE:-1}
[ -f "$shim" ] || { echo "FAIL: no $shim (build fp_enospc_shim)"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# the header fits, the first chunks of frames do not
FP_ENOSPC_MATCH=.fptake FP_ENOSPC_AFTER=3000 LD_PRELOAD="$shim${LD_PRELOAD:+:$LD_PRELOAD}" \
    "$fp" live -q --rig none --input "replay:$rec,loop=1" --mapping anchored,auto=0 --size 320x240 \
    --take-dir "$tmp/takes" --slate fd \
    --script "wait frames 5; key T; wait seconds $((2 * scale)); print messages; print hud; close" \
    >"$tmp/out" 2>"$tmp/err"
rc=$?
cat "$tmp/out" "$tmp/err"
[ $rc -eq 73 ] || { echo "FAIL: live exited $rc, want 73 (a take not written whole)"; exit 1; }
grep -q "^message .*take 1 not written whole: .*fd_T001.fptake: .*No space left on device" "$tmp/out" ||
    { echo "FAIL: the full disk was not said while the session went on"; exit 1; }
tail -n 1 "$tmp/err" | grep -q "take 1 not written whole: .*fd_T001.fptake" ||
    { echo "FAIL: the run's end does not name the take that failed"; exit 1; }
"$fp" info "$tmp/takes/fd_T001.fptake" >"$tmp/info" 2>&1 ||
    { echo "FAIL: the cut take does not read back"; cat "$tmp/info"; exit 1; }
echo "PASS"
