#!/bin/bash
# Two performers' right hands over OSC (issue 55, item 4: "two right hands from two performers
# are two hands"), on loopback and on the recordings' clock:
#  - one process: performer A's right hand (three-claps, hands=right) and performer B's (grab,
#    workspace=0: placed as it arrives, as a live tracker's) with performer=B;
#  - two processes: A runs its right hand and `--input osc:PORT,filter=off,clock=recording,
#    performer=B`; B (`facepuppet monitor`) replays grab with forward=osc:127.0.0.1:PORT.
#    A's face must be the one process's byte for byte (B's hands its own performer's, placed
#    by B's own placement), and another than A's with the same OSC input without performer=
#    (B's right hand overwriting A's, as before).
# SPDX-License-Identifier: GPL-3.0-or-later
set -uo pipefail
build=${FP_BUILD_DIR:-build}
data=${FP_SHARED_DATA:-../shared/data}
fp="$build/bin/facepuppet"
pd=(--plugin-dir "$build/lib/facepuppet")
claps="replay:$data/hands/leap-motion/three-claps_joints_mm.csv,hands=right"
grab="replay:$data/hands/leap-motion/grab_joints_mm.csv,workspace=0"
fail() { echo "FAIL: $*"; exit 1; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-forward-perf-XXXXXX")
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$tmp"' EXIT
. "$(dirname "$0")/listen.sh"
moved() { grep -o 'vertices moved [0-9]* of [0-9]*' "$1"; }

"$fp" run "${pd[@]}" --input "$claps" --input "$grab,performer=B" -o "$tmp/one.obj" -q \
    >"$tmp/one.out" 2>"$tmp/one.err" || { cat "$tmp/one.err"; fail "the one process"; }
grep -q "2 performers" "$tmp/one.err" || { cat "$tmp/one.err"; fail "the one process has not two performers"; }
echo "one process, performer=B: $(moved "$tmp/one.out")"

# two_processes NAME KEYS: A with osc:PORT,filter=off,clock=recording,KEYS; B forwards grab
two_processes() {
    local name=$1 keys=$2
    listen_run "$name" 120 --input "$claps" --input "osc:@PORT@,filter=off,clock=recording$keys"
    "$fp" monitor "${pd[@]}" "$grab,forward=osc:127.0.0.1:$port" >/dev/null 2>"$tmp/$name.b.err" ||
        { cat "$tmp/$name.b.err"; fail "B (monitor) exited $?"; }
    wait $run_pid || { cat "$tmp/$name.err"; fail "A ($name) exited $?"; }
    echo "two processes, $name: $(moved "$tmp/$name.out")"
}
two_processes two ",performer=B"
grep -q "performer 'B': osc (input 2)" "$tmp/two.err" || { cat "$tmp/two.err"; fail "A does not say B's input is B's"; }
cmp -s "$tmp/one.obj" "$tmp/two.obj" || fail "A's face is not the one process's"
two_processes merged ""
cmp -s "$tmp/two.obj" "$tmp/merged.obj" && fail "performer=B gives the face of one performer's hands"
echo "PASS"
