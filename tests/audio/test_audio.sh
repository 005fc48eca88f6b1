#!/bin/bash
# Audio, stage timecode and the audio input (issue 54, items 4-6), end to end:
#  1. speech: three spoken syllables ("ma", "pa", "la", espeak-ng; sox tone bursts where
#     espeak-ng is missing) placed by sox at known onsets between silences.
#  2. sync: run --audio speech.wav --audio-out file:out.wav --audio-offset 0.25 over a real
#     recording (anchored) writes the soundtrack's samples from 0.25 s on, found within one
#     60 fps frame (fp_audio_testtool sync); the take records the file, crc32 and offset;
#     play --audio-out file:play.wav of the take is in sync the same way. The measurement
#     itself must fail against a wrong offset (0.25 s off).
#  3. refusals before the performance: a missing or unreadable sound file exits 66, an
#     unknown device 64, each with its reason and no take or output written.
#  4. LTC at 25 and 29.97 drop-frame, made with libltc's encoder (crossing a dropped minute):
#     run --timecode ltc:FILE.wav gives a take whose timecode_in and every frame's timecode
#     equal the encoded ones (as libltc counted them); `info` on the file says its rate and
#     the timecode at its first sample; also at 24 fps with two frames misread, and on
#     the second channel of a stereo file, and cut mid-frame (the frame in progress at its
#     first sample).
#  5. input-audio: run --input audio:speech.wav (anchored, and onehand with no hand): jaw.open above 0.3 within two frames of each
#     syllable's onset, below 0.1 in the silences (0.25 s after each syllable's end on); the
#     check must fail for onsets moved 0.1 s early; `plugins check` passes input-audio (its
#     channel events well-formed); `monitor` prints them by name and value; a channel name
#     with a space is refused before any work.
#  6. --audio-in file:ramp.wav (an emulated microphone heard in real time, every sample saying
#     where it is): the take's SLATE_TNNN.mic.wav spans its frames (last frame's end, within
#     1/60 s), is one run of the ramp without a gap or a repeat, and the header names it; an
#     unknown device exits 64, a missing file 66, no --take-dir 64, before any work; a run
#     killed (-9) mid-take leaves the WAV readable up to the kill.
#  7. export of the take of 2 (and of a stack over it) writes NAME.wav beside the animation:
#     bit for bit the soundtrack's samples under the exported frames (from the first's
#     soundtrack time, for the frames' span + one period), also for --range 30-90; an
#     existing NAME.wav without --force is refused (73) before any frame.
# Usage: test_audio.sh PATH/TO/fp_audio_testtool (from the source root; FP_BUILD_DIR: build).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
tool=${1:-$build/tests/fp_audio_testtool}
pd=(--plugin-dir "$build/lib/facepuppet")
csv=../shared/data/hands/leap-motion/three-claps_joints_mm.csv
mesh=../shared/data/faces/ict-facekit/generic_neutral_mesh.obj
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-audio-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
command -v sox >/dev/null || fail "sox is missing (Debian: sox; tools/debian-packages.txt)"
[ -f "$csv" ] && [ -f "$mesh" ] || fail "shared data missing: $csv, $mesh"

# ---- 1. speech ---------------------------------------------------------------------------
i=0
for w in ma pa la; do
    if command -v espeak-ng >/dev/null; then
        espeak-ng -s 120 -w "$tmp/raw$i.wav" "$w" || fail "espeak-ng"
        # trimmed to the voice (1% of full scale) at both ends: the onset is the file's start
        sox "$tmp/raw$i.wav" -r 48000 -c 1 "$tmp/syl$i.wav" silence 1 0.005 1% reverse silence 1 0.005 1% reverse ||
            fail "sox trim"
    else
        sox -n -r 48000 -c 1 "$tmp/syl$i.wav" synth 0.4 sawtooth $((120 + 30 * i)) fade 0.005 0.4 0.05 || fail "sox synth"
    fi
    i=$((i + 1))
done
sox -n -r 48000 -c 1 "$tmp/sil6.wav" trim 0 0.6 && sox -n -r 48000 -c 1 "$tmp/sil7.wav" trim 0 0.7 || fail "sox silence"
sox "$tmp/sil6.wav" "$tmp/syl0.wav" "$tmp/sil7.wav" "$tmp/syl1.wav" "$tmp/sil7.wav" "$tmp/syl2.wav" "$tmp/sil6.wav" \
    "$tmp/speech.wav" || fail "sox concatenation"
read -r L0 L1 L2 < <(for i in 0 1 2; do soxi -D "$tmp/syl$i.wav"; done | xargs)
onsets=$(awk -v a="$L0" -v b="$L1" 'BEGIN { printf "%.4f,%.4f,%.4f", 0.6, 1.3 + a, 2.0 + a + b }')
ends=$(awk -v a="$L0" -v b="$L1" -v c="$L2" 'BEGIN { printf "%.4f,%.4f,%.4f", 0.6 + a, 1.3 + a + b, 2.0 + a + b + c }')
echo "speech: $(soxi -D "$tmp/speech.wav") s, syllables at $onsets s, ending at $ends s"

# ---- 2. sync ------------------------------------------------------------------------------
"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --speed 3 --duration 2 --take-dir "$tmp/takes" \
    --slate speech --audio "$tmp/speech.wav" --audio-out "file:$tmp/out.wav" --audio-offset 0.25 \
    -o "$tmp/run.obj" -q >"$tmp/run.out" 2>"$tmp/run.err" || { cat "$tmp/run.err"; fail "run --audio exited $?"; }
cat "$tmp/run.err"
take="$tmp/takes/speech_T001.fptake"
[ -f "$take" ] || fail "no take"
"$tool" sync "$tmp/speech.wav" "$tmp/out.wav" 0.25 || fail "run's soundtrack is out of sync"
"$tool" sync "$tmp/speech.wav" "$tmp/out.wav" 0.5 >/dev/null && fail "the sync check passed a wrong offset"
"$fp" info "$take" >"$tmp/info.out" || fail "info exited $?"
crc=$(python3 -c "import zlib,sys; print('%08x' % (zlib.crc32(open(sys.argv[1],'rb').read()) & 0xffffffff))" "$tmp/speech.wav")
grep -q "soundtrack   $tmp/speech.wav (crc32 $crc), offset 0.25 s" "$tmp/info.out" ||
    { cat "$tmp/info.out"; fail "the take does not record the soundtrack, crc32 $crc and offset"; }
grep -qE "format       facepuppet take 1\.([2-9]|[1-9][0-9])$" "$tmp/info.out" || fail "the take is not format 1.2 or later"
"$fp" play "$take" "${pd[@]}" --audio-out "file:$tmp/play.wav" -q || fail "play --audio-out exited $?"
"$tool" sync "$tmp/speech.wav" "$tmp/play.wav" 0.25 || fail "play's soundtrack is out of sync"
"$fp" play "$take" "${pd[@]}" --audio-out "file:$tmp/play.wav" -q 2>"$tmp/exists.err"
[ $? -eq 73 ] || fail "play over an existing --audio-out without --force did not exit 73"
# a soundtrack given by a relative path, the take played from another folder: 66 naming the take's
# soundtrack and --audio (before: "--audio: speech.wav: No such file or directory", though no
# --audio was given); with --audio it plays in sync
abs_fp=$(realpath "$fp") abs_pd=$(realpath "$build/lib/facepuppet") abs_csv=$(realpath "$csv") abs_mesh=$(realpath "$mesh")
(cd "$tmp" && "$abs_fp" run --plugin-dir "$abs_pd" --mesh "$abs_mesh" --input "replay:$abs_csv" --speed 3 --duration 1 \
    --take-dir rel --audio speech.wav --audio-offset 0.25 --audio-out null -o rel.obj -q >/dev/null 2>&1) ||
    fail "run --audio speech.wav (relative) exited $?"
"$fp" play "$tmp/rel/scene1_T001.fptake" "${pd[@]}" --mesh "$mesh" --audio-out "file:$tmp/rel.wav" -q 2>"$tmp/rel.err"
rc=$?
[ $rc -eq 66 ] && grep -q "the take's soundtrack speech.wav is not there from this folder.*--audio FILE" "$tmp/rel.err" ||
    { cat "$tmp/rel.err"; fail "play of a take whose soundtrack is not there: exit $rc, want 66 naming it and --audio"; }
[ ! -e "$tmp/rel.wav" ] || fail "play wrote its --audio-out though the soundtrack is missing"
"$fp" play "$tmp/rel/scene1_T001.fptake" "${pd[@]}" --mesh "$mesh" --audio "$tmp/speech.wav" \
    --audio-out "file:$tmp/rel.wav" -q || fail "play --audio (the soundtrack from here) exited $?"
"$tool" sync "$tmp/speech.wav" "$tmp/rel.wav" 0.25 || fail "play --audio of the relative take is out of sync"

# ---- 3. refusals ---------------------------------------------------------------------------
refuse() { # WANT_STATUS WANT_TEXT ARGS...
    local want=$1 text=$2
    shift 2
    rm -rf "$tmp/refused"
    timeout 60 "$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --duration 1 --take-dir "$tmp/refused" \
        -o "$tmp/refused.obj" -q "$@" >/dev/null 2>"$tmp/refuse.err"
    local rc=$?
    [ $rc -eq "$want" ] || { cat "$tmp/refuse.err"; fail "run $* exited $rc, want $want"; }
    grep -q "$text" "$tmp/refuse.err" || { cat "$tmp/refuse.err"; fail "run $*: no reason '$text'"; }
    [ ! -e "$tmp/refused" ] && [ ! -e "$tmp/refused.obj" ] || fail "run $*: wrote before refusing"
    echo "refused ($rc): $(grep 'facepuppet run' "$tmp/refuse.err")"
}
echo "not a sound file" >"$tmp/garbage.wav"
refuse 66 "No such file" --audio "$tmp/missing.wav" --audio-out null
refuse 65 "not a sound file" --audio "$tmp/garbage.wav" --audio-out null
# a float file whose samples are not all numbers: refused by --audio, the audio input and info
python3 - "$tmp/nan.wav" <<'PY' || fail "python3 nan.wav"
import math, struct, sys
rate, n = 8000, 8000
x = [0.5 * math.sin(2 * math.pi * 220 * i / rate) for i in range(n)]
x[3000:3100] = [float("nan")] * 100
data = b"".join(struct.pack("<f", v) for v in x)
fmt = struct.pack("<HHIIHH", 3, 1, rate, rate * 4, 4, 32)
open(sys.argv[1], "wb").write(b"RIFF" + struct.pack("<I", 4 + 8 + len(fmt) + 8 + len(data)) + b"WAVE" +
                              b"fmt " + struct.pack("<I", len(fmt)) + fmt + b"data" + struct.pack("<I", len(data)) + data)
PY
refuse 65 "sample 3001 of channel 1 (at 0.375 s) is not a finite number" --audio "$tmp/nan.wav" --audio-out null
"$fp" run "${pd[@]}" --mesh "$mesh" --input "audio:$tmp/nan.wav,fast=1" -o "$tmp/refused.obj" -q 2>"$tmp/refuse.err"
[ $? -eq 65 ] && grep -q "sample 3001 of channel 1" "$tmp/refuse.err" && [ ! -e "$tmp/refused.obj" ] ||
    { cat "$tmp/refuse.err"; fail "--input audio: of a file with NaN samples was not refused (65)"; }
"$fp" info "$tmp/nan.wav" >/dev/null 2>"$tmp/refuse.err"
[ $? -eq 65 ] && grep -q "sample 3001" "$tmp/refuse.err" || { cat "$tmp/refuse.err"; fail "info of a file with NaN samples"; }
refuse 64 "no audio output device 'no-such-device-54'" --audio "$tmp/speech.wav" --audio-out no-such-device-54
refuse 66 "No such file" --timecode "ltc:$tmp/missing-ltc.wav"
refuse 65 "no LTC" --timecode "ltc:$tmp/speech.wav"
refuse 65 "no LTC" --timecode "ltc:$tmp/speech.wav" --audio "$tmp/speech.wav" --audio-out "file:$tmp/refused.wav"
[ ! -e "$tmp/refused.wav" ] || fail "a refused run left its --audio-out file"

# ---- 4. LTC ---------------------------------------------------------------------------------
ltc_case() { # NUM DEN START FPS NAME [glitch]
    "$tool" ltc "$tmp/$5.wav" "$1" "$2" "$3" 4 ${6:-} || fail "ltc encoding"
    "$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --speed 3 --duration 3 --fps "$4" \
        --timecode "ltc:$tmp/$5.wav" --take-dir "$tmp/$5" -o "$tmp/$5.obj" -q >/dev/null 2>"$tmp/$5.err" ||
        { cat "$tmp/$5.err"; fail "run --timecode ltc:$5.wav exited $?"; }
    cat "$tmp/$5.err"
    "$tool" timecodes "$tmp/$5/scene1_T001.fptake" "$1" "$2" "$tmp/$5.wav.txt" ||
        fail "$5: the take's timecodes are not the LTC's"
}
ltc_case 25 1 10:00:00:00 25 ltc25
ltc_case 30000 1001 "00:00:59;20" 29.97 ltc2997df
# two frames misread (the first one's seconds, a frame field of 24 at 24 fps): the rate comes
# from the frames' spacing and the timecode from most frames (before: 25 fps from the one
# frame field of 24, and the first frame's wrong seconds as the timecode in)
ltc_case 24 1 01:02:03:04 24 ltc24glitch glitch
"$fp" info "$tmp/ltc24glitch.wav" | grep -q "timecode  LTC at 24 fps, 01:02:03:04 at the first sample" ||
    fail "info of an LTC file with two misread frames: $("$fp" info "$tmp/ltc24glitch.wav" 2>&1)"
# a jump (the generator restarted at 11:00:00:00 after 2 s, 3 s more): the timecode at the first
# sample is the first run's, not the longer second one's carried back (10:59:58:00)
"$tool" ltc "$tmp/jump1.wav" 25 1 10:00:00:00 2 >/dev/null && "$tool" ltc "$tmp/jump2.wav" 25 1 11:00:00:00 3 >/dev/null &&
    sox "$tmp/jump1.wav" "$tmp/jump2.wav" "$tmp/jump.wav" || fail "the LTC file with a jump"
"$fp" info "$tmp/jump.wav" | grep -q "timecode  LTC at 25 fps, 10:00:00:00 at the first sample (.*with jumps)" ||
    fail "info of an LTC file with a jump: $("$fp" info "$tmp/jump.wav" 2>&1)"
# an LTC file cut mid-frame (its first 0.55 frame gone: frame 10:00:00:00 is in progress at the
# first sample, 10:00:00:01 begins 0.45 frame in): the timecode at the first sample, and a
# take's timecode in, are 10:00:00:00 (before: the nearest frame start's, 10:00:00:01, one
# frame ahead of the LTC for every frame of the take); 0.25 frame cut: 10:00:00:00 as before
sox "$tmp/ltc25.wav" "$tmp/ltc-cut55.wav" trim 1056s && sox "$tmp/ltc25.wav" "$tmp/ltc-cut25.wav" trim 480s ||
    fail "sox: the LTC files cut mid-frame"
for cut in 55 25; do
    "$fp" info "$tmp/ltc-cut$cut.wav" | grep -q "timecode  LTC at 25 fps, 10:00:00:00 at the first sample" ||
        fail "info of an LTC file cut 0.$cut frame in: $("$fp" info "$tmp/ltc-cut$cut.wav" 2>&1 | grep timecode)"
done
"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --speed 3 --duration 1 --fps 25 \
    --timecode "ltc:$tmp/ltc-cut55.wav" --take-dir "$tmp/ltc-cut" -o "$tmp/ltc-cut.obj" -q >/dev/null 2>"$tmp/ltc-cut.err" ||
    { cat "$tmp/ltc-cut.err"; fail "run --timecode ltc:ltc-cut55.wav exited $?"; }
grep -q "timecode 10:00:00:00 - 10:00:01:00" "$tmp/ltc-cut.err" || { cat "$tmp/ltc-cut.err"; fail "the take on the cut LTC"; }
# info on a sound file says what it is (before: "unknown format" of a recording): the LTC's
# rate and the timecode it was encoded from, 48 kHz mono, 4 s; the speech has no LTC
"$fp" info "$tmp/ltc25.wav" >"$tmp/info.out" 2>&1 || { cat "$tmp/info.out"; fail "info ltc25.wav exited $?"; }
grep -q "format    sound, 48000 Hz, 1 channel$" "$tmp/info.out" &&
    grep -q "duration  4.000 s" "$tmp/info.out" &&
    grep -q "timecode  LTC at 25 fps, 10:00:00:00 at the first sample" "$tmp/info.out" &&
    grep -q -- "--timecode ltc:$tmp/ltc25.wav" "$tmp/info.out" || { cat "$tmp/info.out"; fail "info of an LTC file"; }
"$fp" info "$tmp/ltc2997df.wav" | grep -q "timecode  LTC at 29.97 fps, 00:00:59;20 at the first sample" ||
    fail "info of a drop-frame LTC file: $("$fp" info "$tmp/ltc2997df.wav" 2>&1)"
"$fp" info "$tmp/speech.wav" | grep -q "timecode  none" || fail "info finds LTC in speech"
# LTC on the second track of a stereo recording, a tone on the first (before: "no LTC", 65:
# only the first channel was decoded): the take's timecodes are the LTC's, info names the track
sox -n -r 48000 -c 1 "$tmp/tone.wav" synth 4 sine 440 vol 0.3 && sox -M "$tmp/tone.wav" "$tmp/ltc25.wav" "$tmp/ltc-ch2.wav" ||
    fail "sox: the stereo LTC file"
cp "$tmp/ltc25.wav.txt" "$tmp/ltc-ch2.wav.txt"
"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --speed 3 --duration 3 --fps 25 \
    --timecode "ltc:$tmp/ltc-ch2.wav" --take-dir "$tmp/ltc-ch2" -o "$tmp/ltc-ch2.obj" -q >/dev/null 2>"$tmp/ltc-ch2.err" ||
    { rc=$?; cat "$tmp/ltc-ch2.err"; fail "run --timecode ltc:ltc-ch2.wav (LTC on channel 2) exited $rc"; }
"$tool" timecodes "$tmp/ltc-ch2/scene1_T001.fptake" 25 1 "$tmp/ltc-ch2.wav.txt" ||
    fail "LTC on channel 2: the take's timecodes are not the LTC's"
"$fp" info "$tmp/ltc-ch2.wav" | grep -q "timecode  LTC at 25 fps, 10:00:00:00 at the first sample (.* on channel 2)" ||
    fail "info of LTC on channel 2: $("$fp" info "$tmp/ltc-ch2.wav" 2>&1)"

# ---- 5. input-audio -------------------------------------------------------------------------
"$fp" run "${pd[@]}" --mesh "$mesh" --input "audio:$tmp/speech.wav,fast=1" --take-dir "$tmp/jaw" \
    -o "$tmp/jaw.obj" -q >/dev/null 2>"$tmp/jaw.err" || { cat "$tmp/jaw.err"; fail "run --input audio exited $?"; }
cat "$tmp/jaw.err"
"$tool" jaw "$tmp/jaw/scene1_T001.fptake" "$onsets" "$ends" || fail "the jaw does not follow the syllables"
# the same under the one-hand mapping with no hand: it leaves jaw.open to the audio while the
# hand rests (before: it set it to neutral every frame, and the jaw never moved)
"$fp" run "${pd[@]}" --mesh "$mesh" --input "audio:$tmp/speech.wav,fast=1" --mapping onehand \
    --take-dir "$tmp/jaw1" -o "$tmp/jaw1.obj" -q >/dev/null 2>"$tmp/jaw1.err" ||
    { cat "$tmp/jaw1.err"; fail "run --input audio --mapping onehand exited $?"; }
"$tool" jaw "$tmp/jaw1/scene1_T001.fptake" "$onsets" "$ends" || fail "onehand: the jaw does not follow the syllables"
early=$(echo "$onsets" | awk -F, '{ printf "%.4f,%.4f,%.4f", $1 - 0.1, $2 - 0.1, $3 - 0.1 }')
"$tool" jaw "$tmp/jaw/scene1_T001.fptake" "$early" "$ends" >/dev/null && fail "the jaw check passed onsets 0.1 s early"
"$fp" plugins check "$build/lib/facepuppet/input-audio.so" --arg "$tmp/speech.wav" >"$tmp/check.out" 2>&1 ||
    { cat "$tmp/check.out"; fail "plugins check of input-audio"; }
grep -E "events|passed" "$tmp/check.out"
# monitor shows its channel events by name and value (before: "type":"unknown" and nothing
# else): jaw.open rises above 0.3 after the first syllable's onset, as the run's jaw did
"$fp" monitor "${pd[@]}" "audio:$tmp/speech.wav,fast=1" >"$tmp/mon.out" 2>"$tmp/mon.err" ||
    { cat "$tmp/mon.err"; fail "monitor audio: exited $?"; }
grep -q '"type":"unknown"' "$tmp/mon.out" && fail "monitor prints an event of the audio input as unknown"
grep '"type":"channel"' "$tmp/mon.out" | grep -v '"name":"jaw.open","value":' >/dev/null &&
    fail "monitor: a channel event without jaw.open's name and value"
awk -F'"value":' '/"type":"channel"/ { v = $2 + 0; if (v > m) m = v } END { exit !(m > 0.3) }' "$tmp/mon.out" ||
    fail "monitor: jaw.open never above 0.3 ($(grep -c channel "$tmp/mon.out") channel events)"
# a channel name an event log could not record (record=) is refused before the performance
"$fp" run "${pd[@]}" --mesh "$mesh" --input "audio:$tmp/speech.wav,fast=1,channel=jaw open" \
    -o "$tmp/bad.obj" -q >/dev/null 2>"$tmp/bad.err" && fail "channel=\"jaw open\" was taken"
grep -q "printable ASCII" "$tmp/bad.err" || { cat "$tmp/bad.err"; fail "channel=\"jaw open\": no reason given"; }
[ ! -e "$tmp/bad.obj" ] || fail "channel=\"jaw open\": an output was written"
# a FIFO where a sound file goes: refused (66) by every reader, never waited on (refuse's
# timeout: 124 where one opened it and waited for a writer, as input-audio did)
mkfifo "$tmp/fifo.wav"
refuse 66 "not a regular file" --input "audio:$tmp/fifo.wav"
refuse 66 "not a regular file" --audio "$tmp/fifo.wav" --audio-out null
refuse 66 "not a regular file" --timecode "ltc:$tmp/fifo.wav"
refuse 66 "not a regular file" --audio-in "file:$tmp/fifo.wav"

# ---- 6. --audio-in ---------------------------------------------------------------------------
"$tool" ramp "$tmp/ramp.wav" 30 || fail "ramp"
"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --duration 2 --take-dir "$tmp/mic" \
    --audio-in "file:$tmp/ramp.wav" -o "$tmp/mic.obj" -q >/dev/null 2>"$tmp/mic.err" ||
    { cat "$tmp/mic.err"; fail "run --audio-in exited $?"; }
cat "$tmp/mic.err"
[ -f "$tmp/mic/scene1_T001.mic.wav" ] || fail "no scene1_T001.mic.wav beside the take"
"$tool" span "$tmp/mic/scene1_T001.fptake" "$tmp/mic/scene1_T001.mic.wav" || fail "the microphone's WAV does not span the take"
"$tool" ramp-check "$tmp/mic/scene1_T001.mic.wav" || fail "the microphone's WAV is not one run of its samples"
"$fp" info "$tmp/mic/scene1_T001.fptake" | grep -q "microphone   scene1_T001.mic.wav (from file:$tmp/ramp.wav)" ||
    fail "the take's header does not name its microphone"
# kill -9 mid-take: the take reads back, and so does its microphone up to the kill (before: it
# was left in a hidden temporary, .scene1_T001.mic.wav.XXXXXX, and the take named a missing file)
"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --take-dir "$tmp/mickill" \
    --audio-in "file:$tmp/ramp.wav" -o "$tmp/mickill.obj" -q >/dev/null 2>&1 &
pid=$!
for _ in $(seq 100); do # until the take holds 30 frames (its first chunk): a second of recording
    sleep 0.1
    [ -f "$tmp/mickill/scene1_T001.fptake" ] &&
        [ "$(stat -c %s "$tmp/mickill/scene1_T001.fptake")" -gt 30000 ] && break
done
sleep 1
kill -9 $pid
wait $pid 2>/dev/null
[ -f "$tmp/mickill/scene1_T001.mic.wav" ] || { ls -a "$tmp/mickill"; fail "kill -9: no scene1_T001.mic.wav beside the take"; }
"$tool" ramp-check "$tmp/mickill/scene1_T001.mic.wav" || fail "kill -9: the microphone's WAV is not one run of its samples"
mic_s=$(soxi -D "$tmp/mickill/scene1_T001.mic.wav" 2>/dev/null)
awk -v d="$mic_s" 'BEGIN { exit !(d >= 1.0) }' || fail "kill -9: the microphone's WAV holds $mic_s s, want 1 s or more"
echo "kill -9: the take's microphone holds $mic_s s"
refuse 64 "no audio input device 'no-such-mic-54'" --audio-in no-such-mic-54
refuse 66 "No such file" --audio-in "file:$tmp/missing-mic.wav"
"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --audio-in "file:$tmp/ramp.wav" -o "$tmp/refused.obj" -q \
    >/dev/null 2>"$tmp/refuse.err"
[ $? -eq 64 ] && grep -q "give --take-dir" "$tmp/refuse.err" || fail "--audio-in without --take-dir was not refused (64)"

# ---- 7. export's soundtrack -------------------------------------------------------------------
"$fp" export "$take" "${pd[@]}" --format pc2 --out "$tmp/exp.pc2" -q || fail "export exited $?"
read -r s0 n0 < <("$tool" take-range "$take" "$tmp/speech.wav" 0 last)
"$tool" range "$tmp/speech.wav" "$tmp/exp.wav" "$s0" "$n0" || fail "export's WAV is not the take's range of the soundtrack"
"$tool" range "$tmp/speech.wav" "$tmp/exp.wav" "$(awk -v s="$s0" 'BEGIN { print s + 0.01 }')" "$n0" >/dev/null &&
    fail "the range check passed a soundtrack 10 ms off"
"$fp" export "$take" "${pd[@]}" --format glb --range 30-90 --out "$tmp/exp30.glb" -q || fail "export --range exited $?"
read -r s1 n1 < <("$tool" take-range "$take" "$tmp/speech.wav" 30 90)
"$tool" range "$tmp/speech.wav" "$tmp/exp30.wav" "$s1" "$n1" || fail "export --range's WAV is not the range's soundtrack"
rm -f "$tmp/exp.pc2"
"$fp" export "$take" "${pd[@]}" --format pc2 --out "$tmp/exp.pc2" -q 2>"$tmp/exp.err"
[ $? -eq 73 ] && grep -q "exp.wav exists" "$tmp/exp.err" && [ ! -e "$tmp/exp.pc2" ] ||
    { cat "$tmp/exp.err"; fail "an existing NAME.wav was not refused (73) before the export"; }
"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv" --speed 3 --duration 1 --take-dir "$tmp/takes" \
    --slate speech --over "$take" --layer brows@20:add -o "$tmp/over.obj" -q >/dev/null 2>"$tmp/over.err" ||
    { cat "$tmp/over.err"; fail "run --over exited $?"; }
"$fp" export "$tmp/takes/speech_S001.fpstack" "${pd[@]}" --format pc2 --out "$tmp/stack.pc2" -q ||
    fail "export of the stack exited $?"
"$tool" range "$tmp/speech.wav" "$tmp/stack.wav" "$s0" "$n0" || fail "the stack's WAV is not its base take's range of the soundtrack"
echo "PASS"
