#!/bin/bash
# A headless `facepuppet run` driven entirely over OSC from loopback (issue 55, item 1):
# tests/link/test_control.py starts the run on the three-claps recording (looped; ICT face,
# anchored with auto=0: only the control surface engages and commits), records takes with a
# slate and take number, engages, commits and stops, does the same with Live Link Face's
# /RecordStart and /RecordStop, checks every command's /fp/status reply, then sends 10,000
# hostile packets and checks they changed nothing. Here: the takes exist with those slates
# and numbers (facepuppet takes --json; llf 5 started and stopped by buttons) and the first one
# plays back with its commit; then play --control's transport on it (test_transport.py) and,
# under Xvfb, live --control.
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
want = [("scene7", 12), ("scene7", 13), ("llf", 3), ("llf", 4), ("llf", 5)]
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
# play --control: the transport (play, stop, seek, the end) on that take
python3 tests/link/test_transport.py "$fp" "$build/lib/facepuppet" "$tmp/takes/scene7_T012.fptake" "$tmp" ||
    fail "play's transport"
# live --control under Xvfb (where xvfb-run is): a take started and stopped over OSC, /fp/quit
if command -v xvfb-run >/dev/null; then
    python3 - "$fp" "$build/lib/facepuppet" "$data" "$tmp" <<'PY' || fail "live --control"
import os, random, select, socket, subprocess, sys, time
sys.path.insert(0, "tests/link")
import fposc
fp, plugdir, data, tmp = sys.argv[1:5]
port = random.randint(20000, 60000)
err = open(os.path.join(tmp, "live.err"), "w")
p = subprocess.Popen(["xvfb-run", "-a", fp, "live", "--plugin-dir", plugdir, "--input",
                      "replay:%s/hands/leap-motion/three-claps_joints_mm.csv,loop=1" % data,
                      "--take-dir", os.path.join(tmp, "live-takes"), "--control", "osc:%d" % port,
                      "--frames", "100000"], stdout=subprocess.DEVNULL, stderr=err)
for _ in range(1200):
    if "listening on port" in open(os.path.join(tmp, "live.err")).read() or p.poll() is not None: break
    time.sleep(0.1)
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0))
def cmd(*a):
    s.sendto(fposc.encode(*a), ("127.0.0.1", port))
    if not select.select([s], [], [], 20)[0]: sys.exit("live: %s unanswered" % a[0])
    r = fposc.decode(s.recv(65536))[1]
    print("  live %-18s -> %s %s slate %s take %d recording %d" % (a[0], r[1], r[2], r[4], r[5], r[6]))
    return r
if cmd("/fp/record/start", "stage", 3)[1:7:5] != ["ok", 1]: sys.exit("live: no take started")
time.sleep(0.5)
if cmd("/fp/record/stop")[6] != 0: sys.exit("live: still recording")
cmd("/fp/quit")
if p.wait(60) != 0: sys.exit("live exited %d" % p.returncode)
if not os.path.exists(os.path.join(tmp, "live-takes", "stage_T003.fptake")): sys.exit("live: no stage_T003")
print("  live: stage_T003.fptake written; /fp/quit closed the window")
PY
else
    echo "(live --control not tried: no xvfb-run)"
fi
echo "PASS"
