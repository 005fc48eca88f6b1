# Sourced by the glove tests that drive the whole product (test_unplug_said_once.sh,
# test_outage_said_briefly.sh): fp-glove-emu on a pty behind a link, fault commands on its
# stdin (glove_say CMD), `facepuppet run` on it with its stderr in $tmp/err.
# Needs fp (facepuppet) and emu (fp-glove-emu) set, emu_args the emulator's extra options
# (optional); sets cal, tmp, link.
cal=../shared/data/cyberglove/GloveCalibrationRight.cal
tmp=$(mktemp -d)
link=$tmp/glove
mkfifo "$tmp/cmd"
"$emu" --csv ../shared/data/hands/leap-motion/grab_cyberglove_like_angles_deg.csv --cal "$cal" \
    --loop --link "$link" ${emu_args:-} <"$tmp/cmd" >"$tmp/emu.out" 2>&1 &
emu_pid=$!
exec 3>"$tmp/cmd"
run_pid=
trap 'exec 3>&-; [ -n "$run_pid" ] && kill $run_pid 2>/dev/null; kill $emu_pid 2>/dev/null; rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; echo "--- run's stderr:"; cat "$tmp/err"; exit 1; }
# wait_for TEXT [COUNT]: until run's stderr holds COUNT lines (default 1) with TEXT (60 s at most)
wait_for() {
    i=0
    while n=$(grep -c "$1" "$tmp/err" 2>/dev/null); [ "${n:-0}" -lt "${2:-1}" ]; do
        i=$((i + 1)); [ $i -gt 600 ] && fail "not ${2:-1} lines with '$1' in 60 s"
        sleep 0.1
    done
}
glove_say() { echo "$1" >&3; }
# run_glove: `facepuppet run` on the emulated glove (120 s at most) once the link is there,
# until its CONNECTED line (run_start: not waiting for it); run_stop: SIGINT, and its exit
# status must be 0.
run_glove() {
    run_start
    wait_for "sensors, right hand"
}
run_start() {
    i=0
    while [ ! -e "$link" ]; do i=$((i + 1)); [ $i -gt 300 ] && fail "the emulator made no $link"; sleep 0.1; done
    "$fp" run --input "cyberglove:$link,cal=$cal" --duration 120 --out "$tmp/out.obj" >"$tmp/out" 2>"$tmp/err" &
    run_pid=$!
}
run_stop() {
    kill -INT $run_pid
    wait $run_pid
    rc=$?
    run_pid=
    [ $rc -eq 0 ] || fail "run exited $rc after SIGINT"
}
