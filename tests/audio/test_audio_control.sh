#!/bin/bash
# A take started mid-run by the control surface (run --control, /fp/record/start) keeps the
# stage's timecode and the soundtrack at its own first frame (an outside audit's finding;
# README "A soundtrack, the stage's timecode", docs/osc.md "Control"):
#  - LTC at 25 fps from 10:00:00:00 (libltc's encoder, fp_audio_testtool ltc) and a ramp
#    soundtrack whose every sample says where it is (fp_audio_testtool ramp);
#  - run --fps 25 --timecode ltc:LTC --audio RAMP --audio-out file:RUN.wav --control, the take
#    started about 1 s in (session frame K) and stopped 0.8 s later, twice;
#  - each take's timecode in is 10:00:00:00 + K frames (the LTC at its first frame), its
#    soundtrack offset K / 25 s, and play --audio-out file:PLAY.wav gives exactly RUN.wav's
#    samples from K / 25 s on (before: timecode 10:00:00:00 and offset 0 for every take, so
#    the takes shared one timecode and played their soundtrack from its start);
#  - with --audio-in file:MIC.wav (an emulated microphone), each take has its microphone WAV
#    beside it spanning its frames to the last one's end (before: the header named
#    SLATE_TNNN.mic.wav and none was written).
# Usage: test_audio_control.sh PATH/TO/fp_audio_testtool (from the source root).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
tool=${1:-$build/tests/fp_audio_testtool}
data=${FP_SHARED_DATA:-../shared/data}
csv=$data/hands/leap-motion/three-claps_joints_mm.csv
mesh=$data/faces/ict-facekit/generic_neutral_mesh.obj
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-audio-control-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
"$tool" ltc "$tmp/ltc.wav" 25 1 10:00:00:00 8 >/dev/null || fail "ltc"
"$tool" ramp "$tmp/ramp.wav" 8 >/dev/null || fail "ramp"
"$tool" ramp "$tmp/mic.wav" 30 >/dev/null || fail "ramp (the microphone)"
python3 - "$fp" "$build/lib/facepuppet" "$mesh" "$csv" "$tmp" <<'PY' || fail "the run driven over OSC"
import os, socket, subprocess, sys, time
sys.path.insert(0, "tests/link")
import fposc
fp, plugdir, mesh, csv, tmp = sys.argv[1:6]
err_path = os.path.join(tmp, "run.err")
p = subprocess.Popen([fp, "run", "--plugin-dir", plugdir, "--mesh", mesh, "--input", "replay:%s,loop=1" % csv,
                      "--fps", "25", "--timecode", "ltc:" + os.path.join(tmp, "ltc.wav"),
                      "--audio", os.path.join(tmp, "ramp.wav"), "--audio-out", "file:" + os.path.join(tmp, "run.wav"),
                      "--audio-in", "file:" + os.path.join(tmp, "mic.wav"),
                      "--take-dir", os.path.join(tmp, "takes"), "--control", "osc:0", "--duration", "7",
                      "-o", os.path.join(tmp, "run.obj"), "-q"],
                     stdout=subprocess.DEVNULL, stderr=open(err_path, "w"))
port = fposc.control_port(p, err_path)
if port is None:
    p.kill(); sys.exit("no control port: " + open(err_path).read())
cmd = fposc.controller(port)
while cmd("/fp/status")[7] < 1.0: time.sleep(0.05)
cmd("/fp/record/start", "stage", 1); time.sleep(0.8); cmd("/fp/record/stop")
time.sleep(0.5)
cmd("/fp/record/start", "stage", 2); time.sleep(0.8); cmd("/fp/record/stop")
cmd("/fp/quit")
if p.wait(60) != 0: sys.exit("run exited %d: %s" % (p.returncode, open(err_path).read()))
PY
for n in 1 2; do
    take="$tmp/takes/stage_T00$n.fptake"
    "$fp" info "$take" >"$tmp/info$n.txt" || fail "info $take"
    [ -f "$tmp/takes/stage_T00$n.mic.wav" ] || { ls "$tmp/takes"; fail "take $n: no microphone WAV beside it"; }
    "$fp" play --plugin-dir "$build/lib/facepuppet" "$take" --audio-out "file:$tmp/play$n.wav" -q \
        -o "$tmp/play$n.obj" >/dev/null 2>"$tmp/play$n.err" || { cat "$tmp/play$n.err"; fail "play $take"; }
    python3 - "$tmp/info$n.txt" "$tmp/run.wav" "$tmp/play$n.wav" "$tmp/takes/stage_T00$n.mic.wav" <<'PY' || fail "take $n"
import re, struct, sys
info = open(sys.argv[1]).read()
k = int(re.search(r"session frames (\d+)\.\.", info).group(1))
tc = re.search(r"^  timecode +(\S+) - ", info, re.M).group(1)
off = float(re.search(r"^  soundtrack .*, offset (\S+) s", info, re.M).group(1))
want = "10:00:%02d:%02d" % (k // 25, k % 25)
print("take from session frame %d: timecode in %s (the LTC there: %s), soundtrack offset %g s" % (k, tc, want, off))
if tc != want: sys.exit("timecode in %s, the LTC at the take's first frame is %s" % (tc, want))
if abs(off - k / 25) > 1e-6: sys.exit("soundtrack offset %g s, the soundtrack was at %g s" % (off, k / 25))
def floats(path):  # a 32-bit float WAV's samples (--audio-out file: writes them)
    d = open(path, "rb").read()
    at = 12
    while d[at:at + 4] != b"data": at += 8 + struct.unpack_from("<I", d, at + 4)[0]
    n = struct.unpack_from("<I", d, at + 4)[0] // 4
    return struct.unpack_from("<%df" % n, d, at + 8)
run, play = floats(sys.argv[2]), floats(sys.argv[3])
first = k * 48000 // 25
if len(play) < 1000 or tuple(run[first:first + len(play)]) != play:
    sys.exit("play's soundtrack (%d samples) is not the run's from sample %d (%g s): it starts at the "
             "soundtrack's sample %d" % (len(play), first, k / 25, round(play[0] * 65536) - 1))
print("play: %d samples, bit for bit the run's from sample %d" % (len(play), first))
frames = int(re.search(r"^  frames +(\d+) ", info, re.M).group(1))
mic = len(floats(sys.argv[4])) / 48000
print("microphone: %.4f s beside a take of %d frames at 25 fps (%.4f s)" % (mic, frames, frames / 25))
if abs(mic - frames / 25) > 0.002: sys.exit("the microphone WAV is %.4f s, the take's frames span %.4f s" % (mic, frames / 25))
PY
done
echo "PASS: takes started over OSC mid-run keep the stage timecode and the soundtrack at their first frame, and record the microphone"
