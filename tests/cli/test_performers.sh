#!/usr/bin/env bash
# Whose hands are whose (issue 55, item 4), with the facepuppet command: `performer=NAME` on
# any input.
#  1. run with two recordings' right hands: without the key one performer (the merge: the
#     second's right hand overwrites the first's); with performer=B on the second two
#     performers, said in the session's line, and another face; the same bytes with
#     --isolate all (the mapping in its helper, the further hands in its shared memory);
#     both inputs naming one performer give the merge's bytes;
#  2. monitor prints the input's "performer" in every line (none without the key);
#  3. a fifth performer, or a NAME that is no name, is refused with exit 64 naming the SPEC;
#  4. a take of two performers performed again (`--input take:FILE`) keeps its performers: one
#     take input each (source=N, performer= and calibration= as recorded, each performer's
#     placement from the take), byte-identical to the run; a take of one performer's two inputs
#     too; source=3 of a take of two inputs, or more inputs than a session takes, is refused
#     with exit 64 naming the take.
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

# 4. (run steps on the recordings' clock: the same events give the same frames, every frame's
#    vertices compared in an --export .pc2)
two_again() { grep -q "session: 2 performers, each with a left and a right hand of their own: the first performer: take (input 1); performer 'B': take (input 2)" "$tmp/$1.err" ||
                  { cat "$tmp/$1.err"; fail "$1: the take's two performers are not two"; }; }
echo '{"scale": 0.1, "rotation": [0.9998, 0, 0.02, 0], "offset": [-4.1, -15.1, 22.9], "left": {"offset": [0.2, 0, 0]}, "right": {"offset": [-0.3, 0.1, 0]}}' >"$tmp/cal-a.json"
echo '{"scale": 0.1, "offset": [-5.6, -16.7, 21.1]}' >"$tmp/cal-b.json"
mesh=(--mesh "$data/faces/ict-facekit/generic_neutral_mesh.obj")
# each performer placed by a calibration=FILE: the take performed again is the run, bit for bit
run rec "${mesh[@]}" --input "$claps,calibration=$tmp/cal-a.json" --input "$grab,performer=B,calibration=$tmp/cal-b.json" \
    --take-dir "$tmp/takes" --slate s --export "$tmp/rec.pc2"
run again "${mesh[@]}" --input "take:$tmp/takes/s_T001.fptake,fast=1" --export "$tmp/again.pc2"
two_again again
cmp -s "$tmp/again.obj" "$tmp/rec.obj" || fail "a take of two performers performed again differs from its run"
cmp -s "$tmp/again.pc2" "$tmp/rec.pc2" || fail "a take of two performers performed again: its frames (--export .pc2) differ from the run's"
rm -f "$tmp/again.pc2" "$tmp/rec.pc2" # (72 MB each)
# the header's per-hand calibration is the first performer's placement of that hand (its
# offset plus the hand's), the rotation as placed
"$fp" info "$tmp/takes/s_T001.fptake" >"$tmp/info1.txt" 2>&1 || { cat "$tmp/info1.txt"; fail "info of the take failed"; }
grep -q "^  calibration  right: scale 0.1 mesh units/mm, offset -4.4 -15 22.9$" "$tmp/info1.txt" &&
    grep -q "^  calibration  left: scale 0.1 mesh units/mm, offset -3.9 -15.1 22.9$" "$tmp/info1.txt" ||
    { cat "$tmp/info1.txt"; fail "the take's calibration is not the first performer's placement of each hand"; }
python3 - "$tmp/takes/s_T001.fptake" <<'PY' || fail "the take's calibration lost the rotation"
import json, math, struct, sys
b, off = open(sys.argv[1], 'rb').read(), 16
while b[off + 4:off + 8] != b'HEAD':
    off += 20 + struct.unpack_from('<I', b, off + 8)[0]
h = json.loads(b[off + 16:off + 16 + struct.unpack_from('<I', b, off + 8)[0]])
n = math.hypot(0.9998, 0.02)
for c in h['calibration'] + [h['performers'][0]]:
    assert all(abs(a - e) < 1e-12 for a, e in zip(c['rotation'], [0.9998 / n, 0, 0.02 / n, 0])), c
PY
cmp -s "$tmp/again.obj" "$tmp/merged.obj" && fail "a take of two performers performed again gives the merge"
# one take input for all (performer= given: no split): every hand the one performer's, not the run
run one "${mesh[@]}" --input "take:$tmp/takes/s_T001.fptake,fast=1,performer=X"
grep -q "2 performers" "$tmp/one.err" && fail "performer= on the take input still splits it"
cmp -s "$tmp/one.obj" "$tmp/rec.obj" && fail "one take input for both performers gives the two performers' face"
# placed by default (each by their own recording's workspace): the take holds every
# performer's placement (take format 1.3, "performers"), so performed again it is the run,
# bit for bit (before 1.3 every performer came back placed by the first one's)
run rec2 "${mesh[@]}" --input "$claps" --input "$grab,performer=B" --take-dir "$tmp/takes" --slate d
run again2 "${mesh[@]}" --input "take:$tmp/takes/d_T001.fptake,fast=1"
two_again again2
cmp -s "$tmp/again2.obj" "$tmp/rec2.obj" || fail "a take of two performers placed by default performed again differs from its run"
cmp -s "$tmp/again2.obj" "$tmp/merged.obj" && fail "a take of two performers (placed by default) performed again gives the merge"
"$fp" info "$tmp/takes/d_T001.fptake" >"$tmp/info2.txt" 2>&1 || { cat "$tmp/info2.txt"; fail "info of the take failed"; }
grep -q "^  performer    (the first): scale " "$tmp/info2.txt" && grep -q "^  performer    B: scale " "$tmp/info2.txt" ||
    { cat "$tmp/info2.txt"; fail "info does not show each performer's placement"; }
# one performer, two inputs: split too (each input's filter and clock its own again), so the
# take performed again is its run bit for bit; one take input for both is not
run rec3 "${mesh[@]}" --input "$claps" --input "$grab" --take-dir "$tmp/takes" --slate m
run again3 "${mesh[@]}" --input "take:$tmp/takes/m_T001.fptake,fast=1"
grep -q "2 performers" "$tmp/again3.err" && fail "a take of one performer's two inputs came back as two performers"
cmp -s "$tmp/again3.obj" "$tmp/rec3.obj" || fail "a take of one performer's two inputs performed again differs from its run"
# source=N beyond the take's inputs; more inputs than a session takes
"$fp" run -q "${pd[@]}" --input "take:$tmp/takes/s_T001.fptake,fast=1,source=3" --out "$tmp/src3.obj" >"$tmp/src3.out" 2>&1
rc=$?
[ $rc -eq 64 ] || { cat "$tmp/src3.out"; fail "source=3 of a take of 2 inputs: exit $rc, want 64"; }
grep -qF "take: $tmp/takes/s_T001.fptake: source=3: the take has 2 inputs (source=1 to 2)" "$tmp/src3.out" ||
    { cat "$tmp/src3.out"; fail "source=3: the refusal does not name the take"; }
seven=()
for i in 1 2 3 4 5 6 7; do seven+=(--input "$grab"); done
"$fp" run -q "${pd[@]}" "${seven[@]}" --input "take:$tmp/takes/s_T001.fptake" --out "$tmp/nine.obj" >"$tmp/nine.out" 2>&1
rc=$?
[ $rc -eq 64 ] || { cat "$tmp/nine.out"; fail "a take of 2 inputs beside 7 others: exit $rc, want 64"; }
grep -qF -- "--input take:$tmp/takes/s_T001.fptake: the take has 2 inputs (2 performers), one take input each (source=N): 9 --input in all, at most 8" "$tmp/nine.out" ||
    { cat "$tmp/nine.out"; fail "nine inputs: the refusal does not name the take"; }
[ -e "$tmp/src3.obj" ] || [ -e "$tmp/nine.obj" ] && fail "a refused take input wrote a mesh"
echo "ok"
