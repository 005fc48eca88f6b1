#!/bin/bash
# run --over --layer with --control (an outside audit's finding; docs/stack.md "Commands"):
# every take the control surface starts and stops is a pass, and each gets its stack, named
# for the take's slate, as the one pass a run without --control records does:
#  - a base take (three claps, ICT face);
#  - run --over it --layer mouth --control osc:0 on grab (looped), driven over loopback:
#    /fp/record/start pass 1, stop; /fp/record/start pass 2, stop; /fp/record/start other 1,
#    then /fp/quit while it records;
#  - three stacks: pass_S001 (pass_T001 on top), pass_S002 (pass_T002), other_S001
#    (other_T001), each over the base; play of each exits 0. Before: no stack for the takes
#    stopped over OSC, and the last one's named for the run's slate (scene1_S001).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
pd=(--plugin-dir "$build/lib/facepuppet")
data=${FP_SHARED_DATA:-../shared/data}
mesh=$data/faces/ict-facekit/generic_neutral_mesh.obj
claps=$data/hands/leap-motion/three-claps_joints_mm.csv
grab=$data/hands/leap-motion/grab_joints_mm.csv
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-stack-control-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
takes="$tmp/takes"
"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$claps,fast=1" --take-dir "$takes" --slate face \
    -o "$tmp/base.obj" -q >/dev/null 2>"$tmp/base.err" || { cat "$tmp/base.err"; fail "base run exited $?"; }
python3 - "$fp" "$build/lib/facepuppet" "$mesh" "$grab" "$takes" "$tmp" <<'PY' || fail "the run driven over OSC"
import os, socket, subprocess, sys, time
sys.path.insert(0, "tests/link")
import fposc
fp, plugdir, mesh, grab, takes, tmp = sys.argv[1:7]
err_path = os.path.join(tmp, "run.err")
p = subprocess.Popen([fp, "run", "--plugin-dir", plugdir, "--mesh", mesh, "--input", "replay:%s,loop=1" % grab,
                      "--take-dir", takes, "--over", os.path.join(takes, "face_T001.fptake"), "--layer", "mouth",
                      "--control", "osc:0", "--duration", "30", "-o", os.path.join(tmp, "run.obj"), "-q"],
                     stdout=subprocess.DEVNULL, stderr=open(err_path, "w"))
port = fposc.control_port(p, err_path)
if port is None:
    p.kill(); sys.exit("no control port: " + open(err_path).read())
cmd = fposc.controller(port)
for slate, take in (("pass", 1), ("pass", 2), ("other", 1)):
    cmd("/fp/record/start", slate, take); time.sleep(0.5)
    if slate == "pass": cmd("/fp/record/stop")
cmd("/fp/quit")
if p.wait(60) != 0: sys.exit("run exited %d: %s" % (p.returncode, open(err_path).read()))
print(open(err_path).read(), end="")
PY
for st in pass_S001:pass_T001 pass_S002:pass_T002 other_S001:other_T001; do
    stack="$takes/${st%%:*}.fpstack" top="${st##*:}.fptake"
    [ -f "$stack" ] || { ls "$takes"; fail "no stack $stack for $top"; }
    grep -q "\"$top\"" "$stack" || fail "$stack does not hold $top"
    grep -q '"face_T001.fptake"' "$stack" || fail "$stack does not hold the base"
    "$fp" play "${pd[@]}" "$stack" -o "$tmp/${st%%:*}.obj" -q >/dev/null 2>"$tmp/play.err" ||
        { cat "$tmp/play.err"; fail "play $stack exited $?"; }
    echo "$stack: $top over face_T001.fptake, plays"
done
n=$(ls "$takes"/*.fpstack | wc -l)
[ "$n" -eq 3 ] || { ls "$takes"; fail "$n stacks, want 3"; }
echo "PASS: each take recorded over OSC with --over is a pass with its own stack"
