#!/usr/bin/env bash
# Whose hands are whose (issue 55, item 4), with the facepuppet command: `performer=NAME` on
# any input.
#  1. run with two recordings' right hands: without the key one performer (the merge: the
#     second's right hand overwrites the first's); with performer=B on the second two
#     performers, said in the session's line, and another face; the same bytes with
#     --isolate all (the mapping in its helper, the further hands in its shared memory);
#     both inputs naming one performer give the merge's bytes;
#  2. monitor prints the input's "performer" in every line (none without the key);
#  3. a fifth performer, or a NAME that is no name, is refused with exit 64 naming the SPEC.
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$(cd "$build" && pwd)/bin/facepuppet"
pd=(--plugin-dir "$(cd "$build" && pwd)/lib/facepuppet")
data=$(cd "${FP_SHARED_DATA:-../shared/data}" && pwd)
claps="replay:$data/hands/leap-motion/three-claps_joints_mm.csv,hands=right,fast=1"
grab="replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-performers-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
# run NAME ARGS...: facepuppet run -q ARGS --out $tmp/NAME.obj; its summary in $tmp/NAME.out
run() { local name=$1; shift
        "$fp" run -q "${pd[@]}" "$@" --out "$tmp/$name.obj" >"$tmp/$name.out" 2>"$tmp/$name.err" ||
            { cat "$tmp/$name.err"; fail "run $name exited $?"; }
        echo "$name: $(grep -o 'vertices moved [0-9]* of [0-9]*' "$tmp/$name.out")"; }

# 1.
run merged --input "$claps" --input "$grab"
run two --input "$claps" --input "$grab,performer=B"
run two_iso --isolate all --input "$claps" --input "$grab,performer=B"
run same --input "$claps,performer=X" --input "$grab,performer=X"
grep -q "2 performers" "$tmp/merged.err" && fail "the merge has two performers"
grep -q "session: 2 performers, each with a left and a right hand of their own: the first performer: replay (input 1); performer 'B': replay (input 2)" "$tmp/two.err" ||
    { cat "$tmp/two.err"; fail "the session does not say who is who"; }
cmp -s "$tmp/two.obj" "$tmp/merged.obj" && fail "performer=B gives the merge's face"
cmp -s "$tmp/two.obj" "$tmp/two_iso.obj" || fail "--isolate all differs from in process with two performers"
cmp -s "$tmp/same.obj" "$tmp/merged.obj" || fail "one named performer differs from the merge without names"

# 2.
"$fp" monitor "${pd[@]}" --count 5 "$grab,performer=B" >"$tmp/mon.out" 2>"$tmp/mon.err" || fail "monitor exited $?"
[ "$(grep -c '"performer":"B"' "$tmp/mon.out")" -eq 5 ] || { cat "$tmp/mon.out"; fail "monitor does not name the performer"; }
"$fp" monitor "${pd[@]}" --count 5 "$grab" >"$tmp/mon0.out" 2>&1 || fail "monitor exited $?"
grep -q '"performer"' "$tmp/mon0.out" && fail "monitor names a performer without the key"

# 3.
five=()
for p in P1 P2 P3 P4 P5; do five+=(--input "$grab,performer=$p"); done
"$fp" run -q "${pd[@]}" "${five[@]}" --out "$tmp/five.obj" >"$tmp/five.out" 2>&1
rc=$?
[ $rc -eq 64 ] || { cat "$tmp/five.out"; fail "five performers: exit $rc, want 64"; }
grep -qF "input '$grab,performer=P5': performer=P5: at most 4 performers share a session (P1, P2, P3, P4 so far)" "$tmp/five.out" ||
    { cat "$tmp/five.out"; fail "five performers: the refusal does not name the fifth input"; }
[ -e "$tmp/five.obj" ] && fail "five performers: a mesh was written"
"$fp" monitor "${pd[@]}" --count 1 "$grab,performer=B/x" >"$tmp/bad.out" 2>&1
rc=$?
[ $rc -eq 64 ] || { cat "$tmp/bad.out"; fail "performer=B/x: exit $rc, want 64"; }
grep -qF "performer=B/x: expected a name of 1 to 31 letters, digits, '-' or '_'" "$tmp/bad.out" ||
    { cat "$tmp/bad.out"; fail "performer=B/x: no reason given"; }
echo "ok"
