#!/bin/sh
# Isolated inputs (fp_isolate.h): a third party's input runs in a helper process by default
# (--isolate third-party), so that its crash no longer ends the show.
#  - input-crashy (input_crash.c: 20 right-hand samples 10 ms apart, then a fault on its own
#    thread) with a take and -o: `run` exits 0, the take is closed ("ok" in `takes`), the mesh
#    is written; the log names the input and the signal once per fault ("crashy: isolated: the
#    helper process died of SIGSEGV; hands released, restarts in 0.1 s (fault 1 in a row)")
#    and says when the helper is back; the take holds that line and, after it, each hand's
#    release (DISCONNECTED); the same for abort (SIGABRT) and exit (status 3);
#  - faults in a row: after 5 the input is given up, its stream ends, and `run` without
#    --duration ends by itself, exit 0, take closed;
#  - a hang of the input's own thread: the run keeps its pace and ends at --duration; the
#    plugin's stop never returns, so the helper is killed (said) and the run exits 0;
#  - --isolate none keeps it in process: the crash ends the process (139, the old way);
#  - --isolate all on the built-in replay: the same mesh (-o), every frame (--export .pc2) and
#    the same summary as in process, byte for byte.
# Under the sanitizers the helper's SEGV ends as ASan reports it (exit status 1), accepted.
# Args: FACEPUPPET PLUGIN_DIR DATA (from the source root)
set -u
fp=$1 plugins=$2 data=$3
tmp=$(mktemp -d /tmp/fp-isoin-XXXXXX)
trap 'rm -rf "$tmp"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
mesh=$data/faces/mediapipe-canonical/canonical_face_model.obj
rec=$data/hands/leap-motion/Waiting-110fps_joints_mm.csv
segv='died of SIGSEGV|exited with status 1'

# crash NAME CAUSE-PATTERN RUN-ARGS...: a run of crashy with a take in $tmp/NAME
crash() {
    name=$1 cause=$2
    shift 2
    mkdir -p "$tmp/$name"
    timeout 120 "$fp" run --plugin-dir "$plugins" --mesh "$mesh" --take-dir "$tmp/$name" \
        -o "$tmp/$name.obj" "$@" >"$tmp/$name.log" 2>&1
    rc=$?
    [ "$rc" = 0 ] || { sed 's/^/    /' "$tmp/$name.log"; fail "$name: exit $rc, wanted 0"; }
    [ -s "$tmp/$name.obj" ] || fail "$name: -o not written"
    "$fp" takes "$tmp/$name" >"$tmp/$name.takes" 2>&1
    grep -q ' ok ' "$tmp/$name.takes" || { cat "$tmp/$name.takes"; fail "$name: the take is not closed"; }
    grep -Eq "facepuppet: crashy: isolated: the helper process ($cause); hands released" "$tmp/$name.log" ||
        { sed 's/^/    /' "$tmp/$name.log"; fail "$name: the fault is not named ($cause)"; }
    if grep -q "fatal signal" "$tmp/$name.log"; then fail "$name: the host's crash handler spoke"; fi
}

crash segv "$segv" --input crashy --duration 1.5
n=$(grep -Ec "crashy: isolated: the helper process ($segv); hands released, restarts in 0.1 s \(fault 1 in a row\)" "$tmp/segv.log")
[ "$n" = 1 ] || fail "segv: the first fault said $n times, wanted once"
grep -q "crashy: isolated: the helper is back (restart 1, pid [0-9]*)" "$tmp/segv.log" ||
    fail "segv: the helper did not come back"
grep -Eq "^frames [0-9]+," "$tmp/segv.log" || fail "segv: no summary line"
# the take holds the fault and, after it, the hands' release (monitor prints its events)
"$fp" monitor "take:$(ls "$tmp/segv"/*.fptake),fast=1" >"$tmp/segv.events" 2>&1
grep -A2 '"code":"warning","text":"isolated: the helper process' "$tmp/segv.events" | tr -d '\n' |
    grep -q '"hand":"left","code":"disconnected".*"hand":"right","code":"disconnected"' ||
    { head -c 3000 "$tmp/segv.events"; fail "segv: the take has not the fault and the hands released"; }
crash abort 'died of SIGABRT' --input crashy,mode=abort --duration 1
crash exit 'exited with status 3' --input crashy,mode=exit --duration 1

# five in a row: given up, the stream ended, the run ends by itself
crash gaveup "$segv" --input crashy,events=2
grep -Eq "crashy: isolated: the helper process ($segv); hands released; 5 faults in a row: given up" \
    "$tmp/gaveup.log" || fail "gaveup: not given up after 5 faults"

# a hang of its thread: the session keeps going; the stop that never returns is ended
mkdir -p "$tmp/hang"
start=$(date +%s)
timeout 120 "$fp" run --plugin-dir "$plugins" --mesh "$mesh" --input crashy,mode=hang --duration 1 \
    --take-dir "$tmp/hang" -o "$tmp/hang.obj" >"$tmp/hang.log" 2>&1
rc=$? took=$(($(date +%s) - start))
[ "$rc" = 0 ] || { sed 's/^/    /' "$tmp/hang.log"; fail "hang: exit $rc, wanted 0"; }
[ "$took" -lt 30 ] || fail "hang: the run took $took s"
grep -q "crashy: isolated: its stop has not returned within 4 s: the helper process was killed" "$tmp/hang.log" ||
    { sed 's/^/    /' "$tmp/hang.log"; fail "hang: the helper's end not said"; }
"$fp" takes "$tmp/hang" | grep -q ' ok ' || fail "hang: the take is not closed"

# in process, as before: the crash ends the process
timeout 120 "$fp" run --plugin-dir "$plugins" --mesh "$mesh" --input crashy --duration 1.5 --isolate none \
    -o "$tmp/none.obj" >"$tmp/none.log" 2>&1
rc=$?
case $rc in 139|1) ;; *) sed 's/^/    /' "$tmp/none.log"; fail "--isolate none: exit $rc, wanted 139" ;; esac
[ ! -e "$tmp/none.obj" ] || fail "--isolate none: -o written after a crash"

# the built-in replay, isolated (all) and in process: the same bytes
for iso in none all; do
    mkdir -p "$tmp/replay-$iso"
    timeout 300 "$fp" run --mesh "$mesh" --input "replay:$rec" --isolate $iso --take-dir "$tmp/replay-$iso" \
        -o "$tmp/replay-$iso.obj" --export "$tmp/replay-$iso.pc2" >"$tmp/replay-$iso.log" 2>&1 ||
        { sed 's/^/    /' "$tmp/replay-$iso.log"; fail "replay --isolate $iso: exit $?"; }
done
cmp -s "$tmp/replay-none.obj" "$tmp/replay-all.obj" || fail "replay: -o differs isolated"
cmp -s "$tmp/replay-none.pc2" "$tmp/replay-all.pc2" || fail "replay: --export differs isolated"
# (the summary but for the frame's time and the file's name)
same() { grep -E '^frames ' "$1" | sed 's/update median [^;]*;//; s/; wrote .*//'; }
a=$(same "$tmp/replay-none.log") b=$(same "$tmp/replay-all.log")
[ -n "$a" ] && [ "$a" = "$b" ] || fail "replay: summaries differ: '$a' against '$b'"
for iso in none all; do
    "$fp" export "$tmp/replay-$iso"/*.fptake --format pc2 --out "$tmp/take-$iso.pc2" >/dev/null 2>&1 ||
        fail "replay: export of the $iso take"
done
cmp -s "$tmp/take-none.pc2" "$tmp/take-all.pc2" || fail "replay: the takes play differently"
cmp -s "$tmp/take-all.pc2" "$tmp/replay-all.pc2" || fail "replay: the isolated take does not play as it ran"
echo "replay: in process and isolated: $(wc -c <"$tmp/replay-all.pc2") bytes of frames equal, run and take; $a"
# the crash's take plays as it ran
"$fp" export "$tmp/segv"/*.fptake --format obj-seq --out "$tmp/segv-play" >"$tmp/segv-play.log" 2>&1 ||
    { cat "$tmp/segv-play.log"; fail "segv: its take does not play"; }
[ "$fails" = 0 ] && echo "PASS" || { echo "$fails failures"; exit 1; }
