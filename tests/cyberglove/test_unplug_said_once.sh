#!/bin/sh
# A glove unplugged from its box and plugged back, through the whole product: `facepuppet run`
# with a cyberglove input on fp-glove-emu (a pty), the emulator told `unplug` then `plug` on its
# stdin once the previous line showed in run's stderr. The performer must read one line naming
# the device when the glove goes and one when it is back. Before: two lines for the unplug, the
# plugin's ("cyberglove: PATH: glove unplugged ...") and the session's from the status event
# ("cyberglove: glove unplugged ...", without the path).
# Usage: test_unplug_said_once.sh FACEPUPPET FP_GLOVE_EMU   (from the source root)
set -u
fp=$1 emu=$2
. "$(dirname "$0")/glove_run.sh"
run_glove
glove_say unplug
wait_for "unplugged"
sleep 1
glove_say plug
wait_for "plugged into its box again"
sleep 1
run_stop
grep -i "plug" "$tmp/err"
gone=$(grep -c "unplugged" "$tmp/err")
back=$(grep -c "plugged into its box again" "$tmp/err")
[ "$gone" -eq 1 ] || fail "$gone lines say the glove was unplugged (one expected)"
[ "$back" -eq 1 ] || fail "$back lines say the glove is back (one expected)"
grep "unplugged" "$tmp/err" | grep -q "$link" || fail "the unplug line does not name $link"
grep "plugged into its box again" "$tmp/err" | grep -q "$link" || fail "the plug line does not name $link"
echo PASS
