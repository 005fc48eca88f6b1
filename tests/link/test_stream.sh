#!/bin/bash
# The live output stream (issue 55, item 2; docs/osc.md, Stream), received by a test decoder
# written from the document (tests/link/stream_decode.py, the standard library only) and
# compared with the frames written as PC2 (bit for bit the session's):
#  1. `run --stream` of the three-claps recording on the ICT face at its own pace, against the
#     same run's --export PC2: every frame within the stated precision (0.05 mm steps: a vertex
#     within 0.043 mm), 0 frames and 0 packets lost on loopback;
#  2. `play --stream` of the take recorded by that run with FP_STREAM_DROP=0.2:120 (20% of the
#     packets dropped at random in the first 120 frames): every frame from the first keyframe
#     after the drops on is exact again, and no vertex the decoder holds exact is off before;
#  3. the same with 20% dropped all along: no vertex the decoder holds exact is ever off.
# Runs 1 and 2 copy every frame of 1,024 touched vertices or more with the helper thread
# (FP_STREAM_SPLIT=1024; by default only a mesh of 131,072 vertices or more has one), run 3
# copies on the frame thread alone.
# SPDX-License-Identifier: GPL-3.0-or-later
set -uo pipefail
build=${FP_BUILD_DIR:-build}
data=${FP_SHARED_DATA:-../shared/data}
fp="$build/bin/facepuppet"
pd=(--plugin-dir "$build/lib/facepuppet")
face="$data/faces/ict-facekit/generic_neutral_mesh.obj"
fail() { echo "FAIL: $*"; exit 1; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-stream-XXXXXX")
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$tmp"' EXIT

# decode NAME PC2 DECODER-ARGS -- COMMAND...: the decoder listens on a free port first
decode() {
    local name=$1 pc2=$2; shift 2
    local args=()
    while [ "$1" != "--" ]; do args+=("$1"); shift; done
    shift
    for attempt in 1 2 3 4 5; do
        port=$((20000 + RANDOM % 40000))
        python3 tests/link/stream_decode.py --port $port --obj "$face" --pc2 "$pc2" "${args[@]}" \
            >"$tmp/$name.dec" 2>&1 &
        local dec=$!
        for i in $(seq 100); do grep -q "^listening" "$tmp/$name.dec" && break; kill -0 $dec 2>/dev/null || break; sleep 0.1; done
        grep -q "^listening" "$tmp/$name.dec" || { wait $dec; continue; }
        "${@//PORT/$port}" >"$tmp/$name.out" 2>&1 || { cat "$tmp/$name.out"; fail "$name: exit $?"; }
        grep -e "--stream: [0-9]" "$tmp/$name.out"
        wait $dec
        local rc=$?
        sed 's/^/  /' "$tmp/$name.dec"
        [ $rc -eq 0 ] || fail "$name: the decoder"
        return 0
    done
    fail "$name: no free port in 5 tries"
}

# the run's own frames: --export PC2 beside --stream, the replay at its pace
pc2run="$tmp/run.pc2"
FP_STREAM_SPLIT=1024 decode run "$pc2run" -- "$fp" run "${pd[@]}" --mesh "$face" \
    --input "replay:$data/hands/leap-motion/three-claps_joints_mm.csv" --duration 4 \
    --take-dir "$tmp/takes" --slate st --export "$pc2run" -o "$tmp/run.obj" -q --stream osc:127.0.0.1:PORT
take=$(ls "$tmp"/takes/*.fptake)
"$fp" export "$take" --format pc2 --out "$tmp/take.pc2" >/dev/null 2>&1 || fail "export"
FP_STREAM_SPLIT=1024 FP_STREAM_DROP=0.2:120 decode drop120 "$tmp/take.pc2" --clean-after 120 -- \
    "$fp" play "${pd[@]}" "$take" -q --stream osc:127.0.0.1:PORT
grep -q "dropped by FP_STREAM_DROP [1-9]" "$tmp/drop120.out" || fail "drop120: nothing was dropped"
FP_STREAM_DROP=0.2 decode drop "$tmp/take.pc2" --lossy -- \
    "$fp" play "${pd[@]}" "$take" -q --stream osc:127.0.0.1:PORT
echo "PASS"
