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
#  3. the same with 20% dropped all along: no vertex the decoder holds exact is ever off;
#  4. --stream and forward= to an IPv6 address ([::1] and ::1) reach a socket there.
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

# 4. to an IPv6 address, bare or in brackets, from --stream and from an input's forward= (fp_net.h;
#    before: "Address family for hostname not supported" and "Name or service not known"):
#    packets arrive at a socket on [::1]. Skipped where this machine has no IPv6 loopback.
if python3 -c 'import socket; s = socket.socket(socket.AF_INET6, socket.SOCK_DGRAM); s.bind(("::1", 0))' 2>/dev/null; then
    for target in '[::1]' '::1'; do
        for how in stream forward; do
            port=$((20000 + RANDOM % 40000))
            python3 -c '
import socket, sys
s = socket.socket(socket.AF_INET6, socket.SOCK_DGRAM)
s.bind(("::1", int(sys.argv[1])))
s.settimeout(20)
print("listening", flush=True)
n = 0
try:
    while n < 3:
        s.recv(65536)
        n += 1
except socket.timeout:
    pass
print("packets", n)
' $port >"$tmp/v6.out" 2>&1 &
            rx=$!
            for i in $(seq 50); do grep -q listening "$tmp/v6.out" && break; sleep 0.1; done
            if [ $how = stream ]; then
                extra=(--stream "osc:$target:$port"); spec="replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1"
            else
                extra=(); spec="replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1,forward=osc:$target:$port"
            fi
            "$fp" run "${pd[@]}" --mesh "$face" --input "$spec" "${extra[@]}" -o "$tmp/v6.obj" --force -q \
                >"$tmp/v6.run" 2>&1 || { cat "$tmp/v6.run"; fail "$how to $target: exit $?"; }
            wait $rx
            grep -q "packets 3" "$tmp/v6.out" || { cat "$tmp/v6.out" "$tmp/v6.run"; fail "$how to $target: no packets on [::1]"; }
            echo "$how to osc:$target:PORT: packets arrive on [::1]"
        done
    done
else
    echo "no IPv6 loopback: the IPv6 targets skipped"
fi
echo "PASS"
