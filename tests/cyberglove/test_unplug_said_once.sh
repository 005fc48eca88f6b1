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
cal=../shared/data/cyberglove/GloveCalibrationRight.cal
tmp=$(mktemp -d)
link=$tmp/glove
mkfifo "$tmp/cmd"
"$emu" --csv ../shared/data/hands/leap-motion/grab_cyberglove_like_angles_deg.csv --cal "$cal" \
    --loop --link "$link" <"$tmp/cmd" >"$tmp/emu.out" 2>&1 &
emu_pid=$!
exec 3>"$tmp/cmd"
run_pid=
trap 'exec 3>&-; [ -n "$run_pid" ] && kill $run_pid 2>/dev/null; kill $emu_pid 2>/dev/null; rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; echo "--- run's stderr:"; cat "$tmp/err"; exit 1; }
# wait_for TEXT: until run's stderr holds TEXT (60 s at most)
wait_for() {
    i=0
    while ! grep -q "$1" "$tmp/err" 2>/dev/null; do
        i=$((i + 1)); [ $i -gt 600 ] && fail "no line with '$1' in 60 s"
        sleep 0.1
    done
}
i=0
while [ ! -e "$link" ]; do i=$((i + 1)); [ $i -gt 300 ] && fail "the emulator made no $link"; sleep 0.1; done
"$fp" run --input "cyberglove:$link,cal=$cal" --duration 120 --out "$tmp/out.obj" >"$tmp/out" 2>"$tmp/err" &
run_pid=$!
wait_for "sensors, right hand"
echo unplug >&3
wait_for "unplugged"
sleep 1
echo plug >&3
wait_for "plugged into its box again"
sleep 1
kill -INT $run_pid
wait $run_pid
rc=$?
run_pid=
[ $rc -eq 0 ] || fail "run exited $rc after SIGINT"
grep -i "plug" "$tmp/err"
gone=$(grep -c "unplugged" "$tmp/err")
back=$(grep -c "plugged into its box again" "$tmp/err")
[ "$gone" -eq 1 ] || fail "$gone lines say the glove was unplugged (one expected)"
[ "$back" -eq 1 ] || fail "$back lines say the glove is back (one expected)"
grep "unplugged" "$tmp/err" | grep -q "$link" || fail "the unplug line does not name $link"
grep "plugged into its box again" "$tmp/err" | grep -q "$link" || fail "the plug line does not name $link"
echo PASS
