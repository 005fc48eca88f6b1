#!/bin/bash
# A second performer (issue 55, item 4): performer B's input forwarded to performer A's session
# (forward=osc:HOST:PORT, fp_forward.h), on loopback:
#  - one process with both inputs: the three-claps recording's left hand (replay, hands=left)
#    and its right hand (hands=right, workspace=0: placed as it arrives, as a live tracker's);
#  - two processes on the recordings' clock: A runs the left hand and
#    `--input osc:PORT,filter=off,clock=recording`; B (`facepuppet monitor`) replays the right
#    hand with forward=osc:127.0.0.1:PORT. A steps each frame once B's events up to its time
#    have arrived, the two recordings' time zeros aligned (the forwarded /facepuppet/origin),
#    and ends at B's /facepuppet/end: A's face must be the one process's, vertex for vertex
#    (written the same, to the last digit), whenever B starts and however the packets are paced;
#  - the latency through loopback: B forwards to tests/link/forward_latency.py, which prints
#    each event's arrival minus its time (the host clock both share).
# SPDX-License-Identifier: GPL-3.0-or-later
set -uo pipefail
build=${FP_BUILD_DIR:-build}
data=${FP_SHARED_DATA:-../shared/data}
fp="$build/bin/facepuppet"
pd=(--plugin-dir "$build/lib/facepuppet")
rec="$data/hands/leap-motion/three-claps_joints_mm.csv"
fail() { echo "FAIL: $*"; exit 1; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-forward-XXXXXX")
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$tmp"' EXIT
. "$(dirname "$0")/listen.sh"
summary() { sed -n 's/.*vertices moved \([0-9]*\) of [0-9]*; displacement mean [^;]* max \([0-9.e+-]*\) mm.*/\1 \2/p' "$1"; }

"$fp" run "${pd[@]}" --input "replay:$rec,hands=left" --input "replay:$rec,hands=right,workspace=0" \
    -o "$tmp/one.obj" -q >"$tmp/one.out" 2>&1 || { cat "$tmp/one.out"; fail "the one process"; }
read -r o_moved o_max < <(summary "$tmp/one.out")
[ -n "${o_moved:-}" ] && [ "$o_moved" -gt 0 ] || fail "the one process moved nothing"
echo "one process, both inputs: $o_moved vertices moved, max $o_max mm"

# (B starts a second or more after A: A waits for it; 120 s at most)
listen_run a 120 --input "replay:$rec,hands=left" --input "osc:@PORT@,filter=off,clock=recording"
sleep 1 # (A waits on the clock meanwhile)
"$fp" monitor "${pd[@]}" "replay:$rec,hands=right,workspace=0,forward=osc:127.0.0.1:$port" \
    >"$tmp/b.out" 2>"$tmp/b.err" || { cat "$tmp/b.err"; fail "B (monitor) exited $?"; }
wait $run_pid || { cat "$tmp/a.err"; fail "A exited $?"; }
grep "forwarded" "$tmp/b.err"
grep "problems" "$tmp/a.err"
read -r a_moved a_max < <(summary "$tmp/a.out")
echo "two processes (B forwarding to A): ${a_moved:-?} vertices moved, max ${a_max:-?} mm"
python3 - "$tmp/one.obj" "$tmp/a.obj" "$o_moved" "${a_moved:-0}" "$o_max" "${a_max:-0}" <<'PY' || fail "A's face is not the one process's"
import math, sys
def verts(p): return [tuple(map(float, l.split()[1:4])) for l in open(p) if l.startswith("v ")]
one, two = verts(sys.argv[1]), verts(sys.argv[2])
om, am, ox, ax = int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5]), float(sys.argv[6])
d = max(math.dist(p, q) for p, q in zip(one, two)) * 10   # (the ICT face: 10 mm a unit)
print("largest vertex difference between the two faces: %.4f mm" % d)
if len(one) != len(two): sys.exit("vertex counts differ")
if (am, ax) != (om, ox) or d > 1e-4: sys.exit("the faces differ")
PY
cmp -s "$tmp/one.obj" "$tmp/a.obj" || fail "the two meshes are not written the same"

# a sender that is not a forwarding session (fp-osc-send: no origin) under clock=recording:
# its messages are counted untimed, and run says what it waits for instead of hanging mute
listen_run w 8 --input "replay:$rec,hands=left" --input "osc:@PORT@,clock=recording"
"$build/bin/fp-osc-send" --quiet --port "$port" "$rec" >/dev/null 2>&1
wait $run_pid
grep -q "waiting 3 s for 'osc' to deliver past" "$tmp/w.err" || { cat "$tmp/w.err"; fail "no word of the wait"; }
grep -q "without a time on the sender's recording clock" "$tmp/w.err" || { cat "$tmp/w.err"; fail "untimed not reported"; }
grep "waiting 3 s" "$tmp/w.err"

# the latency through loopback
for attempt in 1 2 3 4 5; do
    port=$((20000 + RANDOM % 40000))
    python3 tests/link/forward_latency.py $port >"$tmp/lat.out" 2>&1 &
    l=$!
    for i in $(seq 100); do grep -q "listening" "$tmp/lat.out" && break; kill -0 $l 2>/dev/null || break; sleep 0.1; done
    grep -q "listening" "$tmp/lat.out" || { wait $l; continue; }
    "$fp" monitor "${pd[@]}" "replay:$rec,forward=osc:127.0.0.1:$port" >/dev/null 2>&1 || fail "monitor"
    wait $l || { cat "$tmp/lat.out"; fail "the latency receiver"; }
    grep "^events" "$tmp/lat.out"
    echo "PASS"
    exit 0
done
fail "no free port for the latency receiver"
