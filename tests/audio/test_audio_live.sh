#!/bin/bash
# live's soundtrack, microphone and stage timecode (issue 54, items 4-5 for live), under
# xvfb-run:
#  1. live --audio speech.wav --audio-out file:out.wav --audio-offset 0.25 --take-dir D
#     --audio-in file:ramp.wav, a take of 40 frames (T ... T): out.wav holds the soundtrack
#     from 0.25 s on (fp_audio_testtool sync: within a 60 fps frame) for the take's span (its
#     last frame's end, within 1/60 s); the take records the file, crc32 and offset, and play
#     of it with --audio-out is in sync the same way; the microphone's WAV beside the take
#     spans it and is one run of its samples.
#  1b. live --over that take --audio speech.wav (no --audio-offset): the pass hears the line
#     where the base take did (0.25 s), in sync; its take records offset 0.25.
#  2. live --timecode ltc:ltc25.wav (25 fps LTC from 10:00:00:00 made with libltc; its first
#     sample is the first take's start): two takes, both at 25 fps with timecode_in one of the
#     LTC's and every frame's timecode the LTC's from there; the second's timecode_in is later
#     than the first's last frame (the LTC ran on between the takes).
#  3. refusals before the window: a missing soundtrack 66, an unknown output or input device
#     64, --audio-in without --take-dir 64.
# Usage: test_audio_live.sh PATH/TO/fp_audio_testtool (from the source root; FP_BUILD_DIR).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
tool=${1:-$build/tests/fp_audio_testtool}
pd=(--plugin-dir "$build/lib/facepuppet")
csv=../shared/data/hands/leap-motion/three-claps_joints_mm.csv
mesh=../shared/data/faces/ict-facekit/generic_neutral_mesh.obj
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-audio-live-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
command -v sox >/dev/null || fail "sox is missing (Debian: sox; tools/debian-packages.txt)"
[ -f "$csv" ] && [ -f "$mesh" ] || fail "shared data missing: $csv, $mesh"
live=("$fp" live "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --size 480x270 -q)
script="wait frames 3; key T; wait frames 40; key T; wait frames 3; close"

# ---- 1. soundtrack and microphone ---------------------------------------------------------
sox -n -r 48000 -c 1 "$tmp/speech.wav" synth 3 sawtooth 150 tremolo 3 90 || fail "sox"
"$tool" ramp "$tmp/ramp.wav" 30 || fail "ramp"
"${live[@]}" --take-dir "$tmp/takes" --audio "$tmp/speech.wav" --audio-out "file:$tmp/out.wav" \
    --audio-offset 0.25 --audio-in "file:$tmp/ramp.wav" --script "$script" >/dev/null 2>"$tmp/live.err" ||
    { cat "$tmp/live.err"; fail "live --audio exited $?"; }
cat "$tmp/live.err"
take="$tmp/takes/scene1_T001.fptake"
[ -f "$take" ] || fail "no take"
"$tool" sync "$tmp/speech.wav" "$tmp/out.wav" 0.25 || fail "live's soundtrack is out of sync"
"$tool" sync "$tmp/speech.wav" "$tmp/out.wav" 0.5 >/dev/null && fail "the sync check passed a wrong offset"
"$tool" span "$take" "$tmp/out.wav" || fail "live's soundtrack does not span the take"
crc=$(python3 -c "import zlib,sys; print('%08x' % (zlib.crc32(open(sys.argv[1],'rb').read()) & 0xffffffff))" "$tmp/speech.wav")
"$fp" info "$take" >"$tmp/info.out" || fail "info exited $?"
grep -q "soundtrack   $tmp/speech.wav (crc32 $crc), offset 0.25 s" "$tmp/info.out" ||
    { cat "$tmp/info.out"; fail "the live take does not record the soundtrack, crc32 $crc and offset"; }
grep -q "microphone   scene1_T001.mic.wav" "$tmp/info.out" || fail "the live take does not name its microphone"
"$fp" play "$take" "${pd[@]}" --audio-out "file:$tmp/play.wav" -q || fail "play --audio-out exited $?"
"$tool" sync "$tmp/speech.wav" "$tmp/play.wav" 0.25 || fail "play's soundtrack of the live take is out of sync"
"$tool" span "$take" "$tmp/takes/scene1_T001.mic.wav" || fail "live's microphone does not span the take"
"$tool" ramp-check "$tmp/takes/scene1_T001.mic.wav" || fail "live's microphone is not one run of its samples"

"${live[@]}" --take-dir "$tmp/takes" --over "$take" --layer brows@20:add --audio "$tmp/speech.wav" \
    --audio-out "file:$tmp/over.wav" --script "$script" >/dev/null 2>"$tmp/over.err" ||
    { cat "$tmp/over.err"; fail "live --over --audio exited $?"; }
"$tool" sync "$tmp/speech.wav" "$tmp/over.wav" 0.25 || fail "the pass does not hear the line where the base did"
"$fp" info "$tmp/takes/scene1_T002.fptake" | grep -q "offset 0.25 s" || fail "the pass's take does not record offset 0.25"

# ---- 2. LTC -----------------------------------------------------------------------------------
"$tool" ltc "$tmp/ltc25.wav" 25 1 10:00:00:00 20 || fail "ltc encoding"
two="wait frames 3; key T; wait frames 10; key T; wait frames 20; key T; wait frames 30; key T; wait frames 3; close"
"${live[@]}" --take-dir "$tmp/ltc" --timecode "ltc:$tmp/ltc25.wav" --script "$two" >/dev/null 2>"$tmp/ltc.err" ||
    { cat "$tmp/ltc.err"; fail "live --timecode ltc: exited $?"; }
cat "$tmp/ltc.err"
for t in 1 2; do
    "$tool" timecodes "$tmp/ltc/scene1_T00$t.fptake" 25 1 "$tmp/ltc25.wav.txt" any | tee "$tmp/tc$t.out"
    [ "${PIPESTATUS[0]}" -eq 0 ] || fail "live take $t's timecodes are not the LTC's"
done
f1=$(sed -n 's/.*(last \(.*\))$/\1/p' "$tmp/tc1.out")
k1=$(grep -n "^$f1\$" "$tmp/ltc25.wav.txt" | cut -d: -f1)
k2=$(sed -n "s/.*is the LTC's frame \([0-9]*\)$/\1/p" "$tmp/tc2.out")
[ -n "$k1" ] && [ -n "$k2" ] && [ "$k2" -gt "$k1" ] ||
    fail "take 2's timecode_in (LTC frame ${k2:-?}) is not after take 1's last frame ($f1, LTC frame ${k1:-?})"

# ---- 3. refusals ------------------------------------------------------------------------------
refuse() { # WANT_STATUS WANT_TEXT ARGS...
    local want=$1 text=$2
    shift 2
    rm -rf "$tmp/refused"
    "${live[@]}" --frames 3 "$@" >/dev/null 2>"$tmp/refuse.err"
    local rc=$?
    [ $rc -eq "$want" ] || { cat "$tmp/refuse.err"; fail "live $* exited $rc, want $want"; }
    grep -q "$text" "$tmp/refuse.err" || { cat "$tmp/refuse.err"; fail "live $*: no reason '$text'"; }
    grep -q "OpenGL" "$tmp/refuse.err" && fail "live $*: the window opened before the refusal"
    [ ! -e "$tmp/refused" ] || fail "live $*: wrote before refusing"
    echo "refused ($rc): $(grep 'facepuppet live' "$tmp/refuse.err")"
}
refuse 66 "No such file" --audio "$tmp/missing.wav" --audio-out null
refuse 64 "no audio output device 'no-such-device-54'" --audio "$tmp/speech.wav" --audio-out no-such-device-54
refuse 64 "no audio input device 'no-such-mic-54'" --take-dir "$tmp/refused" --audio-in no-such-mic-54
refuse 64 "give --take-dir" --audio-in "file:$tmp/ramp.wav"
echo "PASS"
