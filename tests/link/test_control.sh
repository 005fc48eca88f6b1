#!/bin/bash
# A headless `facepuppet run` driven entirely over OSC from loopback (issue 55, item 1):
# tests/link/test_control.py starts the run on the three-claps recording (looped; ICT face,
# anchored with auto=0: only the control surface engages and commits), records takes with a
# slate and take number, engages, commits and stops, does the same with Live Link Face's
# /RecordStart and /RecordStop, checks every command's /fp/status reply, then sends 10,000
# hostile packets and checks they changed nothing. Here: the takes exist with those slates
# and numbers (facepuppet takes --json) and the first one plays back with its commit.
# SPDX-License-Identifier: GPL-3.0-or-later
set -uo pipefail
build=${FP_BUILD_DIR:-build}
data=${FP_SHARED_DATA:-../shared/data}
fp="$build/bin/facepuppet"
fail() { echo "FAIL: $*"; exit 1; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-control-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
python3 tests/link/test_control.py "$fp" "$build/lib/facepuppet" \
    "$data/faces/ict-facekit/generic_neutral_mesh.obj" "$data/hands/leap-motion/three-claps_joints_mm.csv" \
    "$tmp/takes" "$tmp" || fail "the OSC client"
"$fp" takes "$tmp/takes" --json >"$tmp/takes.json" || fail "takes --json"
python3 - "$tmp/takes.json" <<'PY' || fail "the takes"
import json, sys
takes = {(t["slate"], t["take"]): t for t in json.load(open(sys.argv[1]))}
want = [("scene7", 12), ("llf", 3), ("llf", 4)]
for k in want:
    if k not in takes: sys.exit("no take %s %d in %s" % (k + (sorted(takes),)))
    if takes[k]["state"] != "ok" or not takes[k]["frames"] > 0:
        sys.exit("take %s %d: state %s, %s frames" % (k + (takes[k]["state"], takes[k]["frames"])))
if len(takes) != len(want): sys.exit("takes %s, wanted only %s" % (sorted(takes), want))
print("takes: " + ", ".join("%s take %d (%d frames)" % (k + (takes[k]["frames"],)) for k in want))
PY
"$fp" play --plugin-dir "$build/lib/facepuppet" "$tmp/takes/scene7_T012.fptake" >"$tmp/play.out" 2>&1 ||
    { cat "$tmp/play.out"; fail "play exited $?"; }
grep "^played" "$tmp/play.out"
grep -q "(scene7 take 12," "$tmp/play.out" || fail "the take does not say scene7 take 12"
grep -q "committed 1" "$tmp/play.out" || fail "the take does not hold the commit"
echo "PASS"
