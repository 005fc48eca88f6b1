#!/bin/bash
# End to end over loopback: `facepuppet run --input osc:PORT` while fp-osc-send replays the
# three-claps recording to it (bundles, timetags, recorded pace); the ICT face must deform.
# The sender reads the Leap playback original (three-claps.json.lz, core/hand/leapjson.h);
# test_osc_live sends a CSV. Then a sender that stops: the input's "no data" line.
# A random high port is tried, and another if it is taken (tests run in parallel).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
csv=${FP_SHARED_DATA:-../shared/data}/hands/leap-motion/three-claps.json.lz
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-osc-run-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
# the recording's volume (mm), as a performer would state their tracker's
box=-100/100/-111/132/292/77
# Wait (up to 60 s) until run PID says in FILE that it listens, or has ended.
wait_listening() {
    local i
    for i in $(seq 600); do
        grep -q "listening on" "$1" && return
        kill -0 "$2" 2>/dev/null || return
        sleep 0.1
    done
}
for attempt in 1 2 3 4 5; do
    port=$((20000 + RANDOM % 40000))
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" \
        --input "osc:$port,box=$box" --duration 4 --out "$tmp/out.obj" >"$tmp/run.out" 2>"$tmp/run.err" &
    run=$!
    # the sender starts once the run listens (opening the face takes a while, longer under
    # the sanitizers: a fixed wait sent the whole recording to a port not yet bound)
    wait_listening "$tmp/run.err" $run
    if ! kill -0 $run 2>/dev/null && grep -q "cannot listen" "$tmp/run.err"; then
        wait $run
        continue
    fi
    grep -q "listening on" "$tmp/run.err" || { cat "$tmp/run.err"; kill $run 2>/dev/null; echo "run did not listen"; exit 1; }
    "$build/bin/fp-osc-send" --port "$port" "$csv" || { echo "fp-osc-send failed"; kill $run; exit 1; }
    wait $run
    rc=$?
    cat "$tmp/run.out"
    grep -v '^ ' "$tmp/run.err"
    [ $rc -eq 0 ] || { echo "facepuppet run exited $rc"; exit 1; }
    moved=$(sed -n 's/.*vertices moved \([0-9]*\) of.*/\1/p' "$tmp/run.out")
    [ -n "$moved" ] && [ "$moved" -gt 0 ] || { echo "the face did not deform"; exit 1; }
    grep -q "problems: none" "$tmp/run.err" || { echo "the osc input counted problems"; exit 1; }
    [ -s "$tmp/out.obj" ] || { echo "no mesh written"; exit 1; }
    echo "ok: $moved vertices moved (port $port)"
    # A sender that stops after 20 frames: 1 s later the input says its hands have no data,
    # the line naming the input once ("facepuppet: osc: left hand: no data from ..."; before:
    # "facepuppet: osc: osc: left hand: ...", the session's source before the plugin's own).
    "$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" -q --input "osc:$port" \
        --duration 3 --out "$tmp/quiet.obj" >"$tmp/quiet.out" 2>"$tmp/quiet.err" &
    run=$!
    wait_listening "$tmp/quiet.err" $run
    "$build/bin/fp-osc-send" --port "$port" --quiet --frames 20 "$csv" || { echo "fp-osc-send failed"; kill $run; exit 1; }
    wait $run
    grep "no data" "$tmp/quiet.err"
    grep -q "^facepuppet: osc: [a-z]* hand: no data from" "$tmp/quiet.err" ||
        { cat "$tmp/quiet.err"; echo "no line says the stopped sender's hands have no data"; exit 1; }
    if grep -q "osc: osc:" "$tmp/quiet.err"; then echo "a line names the input twice"; exit 1; fi
    exit 0
done
echo "no free port found in 5 tries"
exit 1
