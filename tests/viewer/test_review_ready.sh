#!/bin/sh
# The review of a take is made while the performer goes on (run under xvfb-run by ctest):
# `live --take-dir` records a take with T and stops it; its review's session (a session of
# the mesh file: about half a second) is opened on a thread of its own at once, so that V
# later costs no long frame. Shown here by taking the take's file away 2.5 s after it was
# written and pressing V at 5 s: the review opens all the same (badge REVIEW) from what was
# opened before. Before, V opened the file and made the session then (a frame of 0.6-0.7 s on
# this machine's llvmpipe), and here found no take ("no take to review", badge idle).
# Usage: test_review_ready.sh FACEPUPPET   (from the source root)
set -u
fp=$1
data=${FP_SHARED_DATA:-../shared/data}
rec=$data/hands/leap-motion/three-claps_joints_mm.csv
scale=${FP_TEST_TIMEOUT_SCALE:-1}
tmp=$(mktemp -d)
"$fp" live -q --rig none --input "replay:$rec,loop=1" --mapping anchored,auto=0 --size 320x240 \
    --take-dir "$tmp/takes" --slate rv --frames 100000 \
    --script "wait frames 5; key T; wait frames 10; key T; wait seconds $((5 * scale)); key V; wait frames 1;
    print hud; close" >"$tmp/out" 2>"$tmp/err" &
pid=$!
trap 'kill $pid 2>/dev/null; rm -rf "$tmp"' EXIT
i=0
while [ ! -f "$tmp/takes/rv_T001.fptake" ]; do
    i=$((i + 1))
    if [ $i -gt $((600 * scale)) ] || ! kill -0 $pid 2>/dev/null; then
        echo "FAIL: no take written"; cat "$tmp/out" "$tmp/err"; exit 1
    fi
    sleep 0.1
done
sleep $((5 * scale / 2)).$((5 * scale % 2 * 5))
rm "$tmp/takes/rv_T001.fptake"
echo "ok: the take written, taken away 2.5 s later"
wait $pid
rc=$?
cat "$tmp/out"
[ $rc -eq 0 ] || { echo "FAIL: live exited $rc"; cat "$tmp/err"; exit 1; }
grep -q "^hud .* badge REVIEW" "$tmp/out" ||
    { echo "FAIL: V did not show the review of the take opened before"; cat "$tmp/err"; exit 1; }
echo "PASS"
