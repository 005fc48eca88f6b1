#!/bin/sh
# A glove box whose records never match what its probe answers said (fp-glove-emu
# --sensors 18 --claim-sensors 22: ?S and ?N say 22, records carry 18 values), through the
# whole product (`facepuppet run`). Each probe succeeds, then no record of the expected 25
# bytes comes: on stage that must read as an outage, in few lines: the loss once, naming the
# mismatch ("records of 21 bytes, expected 25"), then "still no answer ... after N s" at 10 s;
# no CONNECTED line (no record was ever read), no "line noise" warning per probe.
# Before: every cycle (under a second) said a DISCONNECTED "no well-formed record ..." line,
# a "line noise on PATH" warning and a CONNECTED "...; back after 0.4 s, 1 try" line.
# Usage: test_mismatch_said_briefly.sh FACEPUPPET FP_GLOVE_EMU   (from the source root)
set -u
fp=$1 emu=$2
emu_args="--sensors 18 --claim-sensors 22"
. "$(dirname "$0")/glove_run.sh"
run_start
wait_for "expected 25"
sleep 13
grep "cyberglove: .*$link" "$tmp/err" >"$tmp/said" # (the input's lines about the glove)
echo "--- the input's lines about $link:"; cat "$tmp/said"
lines=$(wc -l <"$tmp/said")
named=$(grep -c "$link: records of 21 bytes, expected 25" "$tmp/said")
up=$(grep -c "sensors, right hand" "$tmp/said")
noise=$(grep -c "line noise" "$tmp/said")
still=$(grep -c "still no answer from $link after [0-9]* s, [0-9]* tries (last: records of 21 bytes" "$tmp/said")
[ "$lines" -eq 2 ] || fail "the mismatch took $lines lines (2 expected: loss, summary)"
[ "$named" -eq 1 ] || fail "$named lines name the mismatch (one expected)"
[ "$up" -eq 0 ] || fail "$up CONNECTED lines for a box that never sent a record it could read"
[ "$noise" -eq 0 ] || fail "$noise line-noise warnings (the loss says it)"
[ "$still" -eq 1 ] || fail "$still summaries after ~14 s (one expected, at 10 s)"
run_stop
echo PASS
