#!/bin/bash
# Hands that arrive (issue 51), end to end over loopback: `facepuppet run --input osc:PORT`
# (no box=: the hands are placed as they arrive) while fp-osc-send replays a recording to it
# on 127.0.0.1 at the recorded pace.
#
#  1. The grab recording deforms the ICT face (anchored) as `run --input replay:` does: the
#     median over 5 runs of the vertices moved and of the max displacement each within 20%
#     of the replay's (issue 51). A single run's frames fall at another phase against the
#     hand's samples (the sender's pace and the machine's load move them), hence the median.
#     The osc input's default filter=auto passes a Leap's (and this sender's facepuppet
#     format's) joints as sent, as the replay does. Measured on 2 cores, since the rig cuts
#     only a drag's push toward bone: the replay 12745 vertices moved, max 26.6 mm; 15 single
#     OSC runs, idle, 12763-12947 moved, max 25.3-30.5 mm (the replay over 20 phases of its
#     frames: 26.1-30.1; docs/performance.md, "Live against replay"). Before, when the rig
#     shrank a whole drag that pushed a little, the max was 6-9 mm and a single run 20-25%
#     under the replay now and then; hence RUN_SERIAL and 5 runs still.
#     Then HandSplay the same way (median of 3 runs of 4 s): a hand that hovers 1.4 s before it
#     reaches, which a live bring-in made after 1 s pushed into the skin at once (the replay
#     pushes nothing; step_arrive.h FP_ARRIVE_BRING_WAIT_S). Then three-claps (median of 3
#     runs of 5 s): two hands, centred between their own centres (fp_pose_auto.h). Both
#     skipped with FP_OSC_LIVE_CSV.
#  2. A hand held still (grab's first row, 6 s; then three-claps', whose pose touched the face
#     before still hands were held out) hovers in front of the face, never reaching it: the
#     run says so (the hint, source "session") within 5 s of the sender starting.
#
# FP_OSC_LIVE_KEYS=",filter=oneeuro" (appended to the osc SPEC) tries the input's keys;
# FP_OSC_LIVE_SEND="--format leap --no-bundle" the sender's options (another address space,
# plain messages timed by their arrival).
# FP_OSC_LIVE_CSV=FILE sends another Leap joints recording instead of grab (e.g. a copy from
# tools/hands-variants); FP_OSC_LIVE_MESH=FILE deforms another face instead of ICT's (the
# bounds stay the grab's on ICT: docs/performance.md "Live against replay on the other faces").
# Free ports: a random high one, another if it is taken (tests run in parallel); every wait
# is bounded. SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
send="$build/bin/fp-osc-send"
pd=(--plugin-dir "$build/lib/facepuppet")
data=${FP_SHARED_DATA:-../shared/data}
mesh=${FP_OSC_LIVE_MESH:-$data/faces/ict-facekit/generic_neutral_mesh.obj}
grab=${FP_OSC_LIVE_CSV:-$data/hands/leap-motion/grab_joints_mm.csv}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-osc-live-XXXXXX")
runpid=
cleanup() { [ -n "$runpid" ] && kill "$runpid" 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }

# "moved max" from a run's summary line (max displacement in mm)
summary() { sed -n 's/.*vertices moved \([0-9]*\) of [0-9]*; displacement mean [^;]* max \([0-9.e+-]*\) mm.*/\1 \2/p' "$1"; }

# osc_run NAME CSV DURATION: `run --input osc:PORT` for DURATION s in the background, the
# sender started once the run listens; sets runpid, t_send (ns) and fills $tmp/NAME.{out,err}
osc_run() {
    local name=$1 csv=$2 dur=$3 attempt port i
    for attempt in 1 2 3 4 5; do
        port=$((20000 + RANDOM % 40000))
        "$fp" run "${pd[@]}" --mesh "$mesh" --input "osc:$port${FP_OSC_LIVE_KEYS:-}" --duration "$dur" \
            --out "$tmp/$name.obj" >"$tmp/$name.out" 2>"$tmp/$name.err" &
        runpid=$!
        for i in $(seq 600); do           # the face loads first: up to 60 s
            grep -q "listening on" "$tmp/$name.err" && break
            kill -0 $runpid 2>/dev/null || break
            sleep 0.1
        done
        if grep -q "listening on" "$tmp/$name.err"; then
            t_send=$(date +%s%N)
            "$send" --quiet --port "$port" ${FP_OSC_LIVE_SEND:-} "$csv" >"$tmp/$name.send" 2>&1 &
            sendpid=$!
            return 0
        fi
        wait $runpid
        runpid=
        grep -q "cannot listen" "$tmp/$name.err" || { cat "$tmp/$name.err"; fail "run did not start"; }
    done
    fail "no free port found in 5 tries"
}

# osc_wait NAME: the sender and the run finished, both well
osc_wait() {
    wait $sendpid || { cat "$tmp/$1.send"; fail "fp-osc-send failed"; }
    wait $runpid
    local rc=$?
    runpid=
    [ $rc -eq 0 ] || { cat "$tmp/$1.err"; fail "facepuppet run exited $rc"; }
    grep -q "problems: none" "$tmp/$1.err" || { cat "$tmp/$1.err"; fail "the osc input counted problems"; }
}

# ---- 1. grab (and HandSplay) over OSC against the replay -------------------------------------
# compare NAME CSV DURATION RUNS: the replay's summary against the median of RUNS osc runs
compare() {
    local name=$1 csv=$2 dur=$3 runs=$4 k m x r_moved r_max mid
    "$fp" run "${pd[@]}" -q --mesh "$mesh" --input "replay:$csv,fast=1" --out "$tmp/$name.replay.obj" \
        >"$tmp/$name.replay.out" 2>"$tmp/$name.replay.err" || { cat "$tmp/$name.replay.err"; fail "the replay run failed"; }
    read -r r_moved r_max < <(summary "$tmp/$name.replay.out")
    [ -n "${r_moved:-}" ] && [ "$r_moved" -gt 0 ] || fail "the replay moved nothing ($name)"
    echo "$name replay: $r_moved vertices moved, max $r_max mm"
    local moved=() maxes=()
    for k in $(seq "$runs"); do
        osc_run "$name$k" "$csv" "$dur"
        osc_wait "$name$k"
        read -r m x < <(summary "$tmp/$name$k.out")
        [ -n "${m:-}" ] || { cat "$tmp/$name$k.out"; fail "no summary"; }
        echo "$name osc run $k: $m vertices moved, max $x mm"
        grep -q "session: hands placed life-size" "$tmp/$name$k.err" || { cat "$tmp/$name$k.err"; fail "no placement line"; }
        ! grep -q "no fingertip came within" "$tmp/$name$k.err" || { cat "$tmp/$name$k.err"; fail "a hint for a hand that reaches"; }
        [ "$m" -gt 0 ] || { cat "$tmp/$name$k.err"; fail "$name osc run $k: the face did not deform"; }
        moved+=("$m")
        maxes+=("$x")
    done
    mid=$(((runs + 1) / 2))
    med_moved=$(printf '%s\n' "${moved[@]}" | sort -n | sed -n ${mid}p)
    med_max=$(printf '%s\n' "${maxes[@]}" | sort -g | sed -n ${mid}p)
    echo "$name osc median: $med_moved vertices moved, max $med_max (replay: $r_moved, $r_max)"
    [ "${FP_TEST_TIME_SCALE:-1}" -gt 1 ] || awk -v a="$med_moved" -v b="$r_moved" 'BEGIN { exit !(a >= 0.8 * b && a <= 1.2 * b) }' ||
        fail "$name: vertices moved over OSC ($med_moved) not within 20% of the replay's ($r_moved)"
    # The max displacement within 20% too (issue 51). Under the sanitizers (FP_TEST_TIME_SCALE
    # > 1) each live frame takes several periods, so the frames the OSC events land in differ
    # from the replay's: there the check is that it deforms (above) with no memory error.
    local tol=0.2
    if [ "${FP_TEST_TIME_SCALE:-1}" -gt 1 ]; then tol=1; fi
    awk -v a="$med_max" -v b="$r_max" -v t="$tol" 'BEGIN { exit !(a >= (1 - t) * b && a <= (1 + t) * b) }' ||
        fail "$name: max displacement over OSC ($med_max mm) not within $tol of the replay's ($r_max mm)"
}
compare grab "$grab" 5 5
# HandSplay (2.65 s): its hand hovers 19-25 mm off the face for 1.4 s, then reaches to 9 mm and
# grabs; the replay needs no bring-in. Before, the live bring-in pushed it 24 mm closer after
# 1 s away, into the skin at once (a grab mid-hover, held to the end): 804 vertices, max 6.9 mm
# against the replay's 4616 and 23.5 (step_arrive.h FP_ARRIVE_BRING_WAIT_S).
[ -n "${FP_OSC_LIVE_CSV:-}" ] || compare handsplay "$data/hands/leap-motion/HandSplay-110fps_joints_mm.csv" 4 3
# three-claps (3.5 s, the demo's): two hands that start 230 mm apart and clap inward. Before,
# the live placement centred on the box of both hands' joints so far, 7 mm to the side of the
# replay's at the first grab: 11011 vertices, max 42.8 mm against 11710 and 31.4 (one run);
# now centred between the hands' own centres (fp_pose_auto.h): 5 runs 11076-11443, 26.8-30.8.
[ -n "${FP_OSC_LIVE_CSV:-}" ] || compare claps "$data/hands/leap-motion/three-claps_joints_mm.csv" 5 3

# ---- 2. a hand that never reaches: the hint within 5 s --------------------------------------
# Held still (a recording's first row for 6 s): still hands are held out, hovering
# (fp_pose_auto.h FP_POSE_STILL_MM), whatever the pose; three-claps' first row touched the face
# before that (its front, a fingertip, at the nose tip's depth).
for still in "$grab" "$data/hands/leap-motion/three-claps_joints_mm.csv"; do
    rm -f "$tmp/still.obj"
    awk -F, -v OFS=, 'NR == 1 { print; next }
                      NR == 2 { for (i = 0; i < 660; i++) { $1 = i; $2 = sprintf("%d", 1000000 + i * 9091); print }; exit }' \
        "$still" >"$tmp/still_joints_mm.csv"
    osc_run still "$tmp/still_joints_mm.csv" 9
    hint_s=
    for i in $(seq 100); do                   # 10 s at most
        if grep -q "session: hands present for .* no fingertip came within" "$tmp/still.err"; then
            hint_s=$(awk -v a="$(date +%s%N)" -v b="$t_send" 'BEGIN { printf "%.2f", (a - b) / 1e9 }')
            break
        fi
        sleep 0.1
    done
    osc_wait still
    grep "no fingertip came within" "$tmp/still.err"
    [ -n "$hint_s" ] || { cat "$tmp/still.err"; fail "no hint for a hand that never reached the face ($still)"; }
    echo "the hint came $hint_s s after the sender started ($(basename "$still"), held still)"
    awk -v s="$hint_s" 'BEGIN { exit !(s <= 5.0) }' || fail "the hint came after $hint_s s (more than 5)"
    [ "$(grep -c "no fingertip came within" "$tmp/still.err")" -eq 1 ] || fail "the hint was said more than once"
    read -r m x < <(summary "$tmp/still.out")
    [ "$m" -eq 0 ] || fail "a hand that never reached moved $m vertices"
done
echo "ok"
