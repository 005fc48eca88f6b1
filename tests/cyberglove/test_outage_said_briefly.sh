#!/bin/sh
# A serial cable pulled for ~13 s and plugged back, through the whole product: `facepuppet run`
# with a cyberglove input on fp-glove-emu (a pty behind --link), told `pull`, then `replug`.
# On stage the outage must take few lines: the loss once, one "still no answer from PATH after
# N s, N tries" (due 10 s after the loss), and the return once, each naming the device. The
# same for a glove that stops answering (`silent` ~13 s, then `answer`).
# Before: a "reopening PATH in 2000 ms (attempt N)" warning at every attempt, every 2 s for as
# long as the glove was gone (10 lines in this test), burying the other messages.
# Usage: test_outage_said_briefly.sh FACEPUPPET FP_GLOVE_EMU   (from the source root)
set -u
fp=$1 emu=$2
. "$(dirname "$0")/glove_run.sh"
run_glove
# outage_lines FIRST N: the input's lines from the first line with FIRST to the Nth CONNECTED
# line, both included (run's progress lines, once a second, aside), into $tmp/outage
outage_lines() {
    awk -v first="$1" -v n="$2" 'index($0, first) {on = 1} on && /cyberglove: / {print}
        /sensors, right hand/ && ++c == n {exit}' "$tmp/err" >"$tmp/outage"
    echo "--- the outage as said:"; cat "$tmp/outage"
}
glove_say pull
wait_for "cable pulled"
sleep 13
glove_say replug
wait_for "sensors, right hand" 2
outage_lines "cable pulled" 2
lines=$(wc -l <"$tmp/outage")
gone=$(grep -c "cable pulled" "$tmp/outage")
still=$(grep -c "still no answer from $link after [0-9]* s, [0-9]* tries" "$tmp/outage")
back=$(grep -c "$link: .*sensors, right hand.*back after [0-9.]* s, [0-9]* tries" "$tmp/outage")
[ "$gone" -eq 1 ] || fail "$gone lines say the cable was pulled (one expected)"
[ "$still" -eq 1 ] || fail "$still lines sum up the outage (one expected after ~13 s)"
[ "$back" -eq 1 ] || fail "$back lines say the glove is back, naming $link and the outage (one expected)"
[ "$lines" -eq 3 ] || fail "the outage took $lines lines (3 expected: loss, summary, return)"
grep "cable pulled" "$tmp/outage" | grep -q "$link" || fail "the loss line does not name $link"
# A glove that stops answering, the port still there: the probes that follow fail for
# another reason ("no answer to ?G"), which is the summary's last reason, not a second loss
# line (before: 'PATH: no answer to ?G (is the glove box on, baud 115200?)' after the loss)
glove_say silent
wait_for "stopped answering"
sleep 13
glove_say answer
wait_for "sensors, right hand" 3
outage_lines "stopped answering" 3
lines=$(wc -l <"$tmp/outage")
grep -q "still no answer from $link after [0-9]* s, [0-9]* tries (last: no answer to ?G" "$tmp/outage" ||
    fail "the summary does not give the last reason"
[ "$lines" -eq 3 ] || fail "the silence took $lines lines (3 expected: loss, summary, return)"
sleep 1
run_stop
echo PASS
