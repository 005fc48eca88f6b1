#!/bin/sh
# A serial cable pulled for ~13 s and plugged back, through the whole product: `facepuppet run`
# with a cyberglove input on fp-glove-emu (a pty behind --link), told `pull`, then `replug`.
# On stage the outage must take few lines: the loss once, one "still no answer from PATH after
# N s, N tries" (due 10 s after the loss), and the return once, each naming the device.
# Before: a "reopening PATH in 2000 ms (attempt N)" warning at every attempt, every 2 s for as
# long as the glove was gone (10 lines in this test), burying the other messages.
# Usage: test_outage_said_briefly.sh FACEPUPPET FP_GLOVE_EMU   (from the source root)
set -u
fp=$1 emu=$2
. "$(dirname "$0")/glove_run.sh"
run_glove
glove_say pull
wait_for "cable pulled"
sleep 13
glove_say replug
wait_for "sensors, right hand" 2
sleep 1
run_stop
# the outage: the input's lines from the loss line to the return line, both included (run's
# progress lines, once a second, aside)
awk '/cable pulled/ {on = 1} on && /cyberglove: / {print} on && /sensors, right hand/ {exit}' \
    "$tmp/err" >"$tmp/outage"
echo "--- the outage as said:"; cat "$tmp/outage"
lines=$(wc -l <"$tmp/outage")
gone=$(grep -c "cable pulled" "$tmp/err")
still=$(grep -c "still no answer from $link after [0-9]* s, [0-9]* tries" "$tmp/err")
back=$(grep -c "$link: .*sensors, right hand.*back after [0-9.]* s, [0-9]* tries" "$tmp/err")
[ "$gone" -eq 1 ] || fail "$gone lines say the cable was pulled (one expected)"
[ "$still" -eq 1 ] || fail "$still lines sum up the outage (one expected after ~13 s)"
[ "$back" -eq 1 ] || fail "$back lines say the glove is back, naming $link and the outage (one expected)"
[ "$lines" -eq 3 ] || fail "the outage took $lines lines (3 expected: loss, summary, return)"
grep "cable pulled" "$tmp/err" | grep -q "$link" || fail "the loss line does not name $link"
echo PASS
