#!/bin/sh
# Isolated mapping plugins (issue 56, items 1-2), as a plugin author outside the project meets
# them: facepuppet installed into a temporary prefix, tests/plugin/map_fault.c built out of
# tree against it with pkg-config as map-steady, map-crash (writes through NULL on session
# frame 29, its 30th) and map-hang (spins forever there). Not shipped with facepuppet, they
# run in a helper process by default (--isolate third-party):
#  - crash and hang: `run --frames-out` exits 0 and writes every frame; the fault is named
#    once (the plugin, the call, the frame, the cause: SIGSEGV, or the deadline); the frames
#    while the helper is away hold frame 28's shape; from the frame the helper is back the face
#    deforms again (frames differ from gain=0's and from the held shape) and the last frame
#    equals the steady plugin's;
#    the take records the fault as a status event, and `play` of it gives the run's frames;
#    the restart is on the frames' clock: with fast=1 and at --speed 2 the crash run gives the
#    real-time run's frames;
#  - --isolate all with the built-in mappings gives bit-identical meshes to in-process runs
#    (every frame: --export .pc2, and the last: -o .obj) on the three faces and the four
#    recordings, the mappings taken in turn (a generous deadline: on a loaded machine a
#    helper may miss 50 ms, and a missed deadline is by design not the same run); and the same
#    for map-steady,commit=1, which reads the frame's base after each commit.
# Under the sanitizers the helper's crash ends as ASan reports it (an exit status, not the
# signal), which the crash's pattern accepts. Args: BUILD_DIR DATA (from the source root)
set -u
build=$(cd "$1" && pwd) data=$2 src=$(pwd)
scale=${FP_TEST_TIMEOUT_SCALE:-1}
deadline=$((500 * scale))
tmp=$(mktemp -d /tmp/fp-isolate-XXXXXX)
trap 'rm -rf "$tmp"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null || { echo "FAIL: install"; exit 1; }
fp=$prefix/bin/facepuppet
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
cflags=$(pkg-config --cflags facepuppet) libs=$(pkg-config --libs facepuppet)
mkdir -m 755 "$tmp/pc"
for m in steady:0 crash:1 hang:2 chaos:3; do
    cc -std=c11 -O2 -Wall -Wextra -Werror -shared -fPIC -fvisibility=hidden $cflags \
       -DFAULT_MODE=${m#*:} -o "$tmp/pc/map-${m%:*}.so" "$src/tests/plugin/map_fault.c" $libs ||
        { echo "FAIL: building map-${m%:*} out of tree"; exit 1; }
done
mesh=$data/faces/mediapipe-canonical/canonical_face_model.obj
rec=$data/hands/leap-motion/Waiting-110fps_joints_mm.csv
frame() { ls "$1"/frame_$(printf %06d "$2")_*.obj 2>/dev/null; }

# fo NAME ARGS...: a run with every frame in $tmp/NAME, its take in $tmp/NAME/take
fo() {
    name=$1
    shift
    mkdir -p "$tmp/$name/take"
    "$fp" run --plugin-dir "$tmp/pc" --mesh "$mesh" --input "replay:$rec" --frames-out "$tmp/$name" \
        --take-dir "$tmp/$name/take" -o "$tmp/$name.obj" "$@" >"$tmp/$name.log" 2>&1
    echo $? >"$tmp/$name.rc"
}
fo steady --mapping steady
fo rest --mapping steady,gain=0
n=$(sed -n 's/^frames \([0-9]*\),.*/\1/p' "$tmp/steady.log")
[ "$(cat "$tmp/steady.rc")" = 0 ] && [ -n "$n" ] && [ "$(ls "$tmp/steady"/frame_*.obj | wc -l)" = "$n" ] ||
    { sed 's/^/    /' "$tmp/steady.log"; echo "FAIL: the steady reference"; exit 1; }

# fault NAME CAUSE-PATTERN
fault() {
    name=$1 cause=$2 d=$tmp/$1
    fo "$name" --mapping "$name" --isolate-deadline "$deadline"
    rc=$(cat "$tmp/$name.rc")
    [ "$rc" = 0 ] || fail "$name: exit $rc, wanted 0"
    got=$(ls "$d"/frame_*.obj 2>/dev/null | wc -l)
    [ "$got" = "$n" ] || fail "$name: $got frames written, wanted every frame ($n)"
    grep -q "^frames $n," "$tmp/$name.log" || fail "$name: the summary has not $n frames"
    named=$(grep -Ec "mapping '$name': isolated: $cause during process \(frame 29\); the last control set is held" "$tmp/$name.log")
    [ "$named" = 1 ] || fail "$name: the fault named $named times, wanted once"
    faults=$(grep -c "the last control set is held" "$tmp/$name.log")
    [ "$faults" = 1 ] || fail "$name: $faults faults reported, wanted 1"
    back=$(sed -n "s/.*mapping '$name': isolated: the helper is back (restart 1, pid [0-9]*) from frame \([0-9]*\)$/\1/p" "$tmp/$name.log")
    if [ -z "$back" ]; then
        fail "$name: the helper did not come back"
        back=$n
    fi
    echo "$name: fault on frame 29, frames held 29..$((back - 1)), the helper back from frame $back of $n"
    k=29
    while [ "$k" -lt "$back" ]; do
        cmp -s "$(frame "$d" 28)" "$(frame "$d" "$k")" || { fail "$name: held frame $k is not frame 28's shape"; break; }
        k=$((k + 1))
    done
    deformed=0 moving=0 same=0
    while [ "$k" -lt "$n" ]; do
        f=$(frame "$d" "$k")
        cmp -s "$f" "$(frame "$tmp/rest" "$k")" || deformed=$((deformed + 1))
        cmp -s "$f" "$(frame "$d" 28)" || moving=$((moving + 1))
        cmp -s "$f" "$(frame "$tmp/steady" "$k")" && same=$((same + 1))
        k=$((k + 1))
    done
    [ "$deformed" -gt 0 ] && [ "$moving" -gt 0 ] || fail "$name: the face does not deform again after the restart"
    cmp -s "$(frame "$d" $((n - 1)))" "$(frame "$tmp/steady" $((n - 1)))" ||
        fail "$name: its last frame is not the steady plugin's"
    echo "$name: after the restart $deformed of $((n - back)) frames deformed, $moving moved from the held shape," \
         "$same equal to the steady plugin's (the engine's guarded steps follow the path: equal again once a gesture ends)"
    take=$(ls "$d"/take/*.fptake)
    grep -aq "mapping '$name' fault: .* during process (frame 29)" "$take" ||
        fail "$name: the take has no fault event"
    mkdir -p "$d/play"
    "$fp" play "$take" --frames-out "$d/play" >"$d/play.log" 2>&1 || fail "$name: play of the take failed"
    k=0
    while [ "$k" -lt "$n" ]; do
        cmp -s "$(frame "$d" "$k")" "$(frame "$d/play" "$k")" || { fail "$name: play's frame $k differs from the run's"; break; }
        k=$((k + 1))
    done
    if [ "$fails" != 0 ]; then sed 's/^/    /' "$tmp/$name.log" | grep -v "^     *[0-9.]* s  frame"; fi
}
fault crash "the helper process (died of SIGSEGV|exited with status [0-9]+)"
fault hang "no answer within the deadline of $deadline ms \(the helper was killed\)"

# The restart is decided on the frames' clock, and the frame it is due on waits for the new
# helper: the crash run again with fast=1 (frames as fast as the machine steps them) and at
# --speed 2 gives the real-time run's frames, every one (before: with fast=1 the run ended
# before the wall clock's 0.1 s had passed, its frames after the fault all held).
for how in fast speed2; do
    if [ $how = fast ]; then input="replay:$rec,fast=1" speed=1; else input="replay:$rec" speed=2; fi
    d=$tmp/crash-$how
    mkdir -p "$d"
    "$fp" run --plugin-dir "$tmp/pc" --mesh "$mesh" --input "$input" --speed $speed --frames-out "$d" \
        --mapping crash --isolate-deadline "$deadline" -o "$d.obj" >"$d.log" 2>&1 || fail "crash $how: exit $?"
    k=0 differ=0
    while [ "$k" -lt "$n" ]; do
        cmp -s "$(frame "$tmp/crash" "$k")" "$(frame "$d" "$k")" || differ=$((differ + 1))
        k=$((k + 1))
    done
    [ "$differ" = 0 ] && cmp -s "$tmp/crash.obj" "$d.obj" ||
        fail "crash $how: $differ of $n frames (or the -o mesh) differ from the real-time run's"
    b1=$(grep -o "the helper is back (restart 1, pid [0-9]*) from frame [0-9]*" "$tmp/crash.log" | sed 's/.* //')
    b2=$(grep -o "the helper is back (restart 1, pid [0-9]*) from frame [0-9]*" "$d.log" | sed 's/.* //')
    [ -n "$b2" ] && [ "$b1" = "$b2" ] || fail "crash $how: the helper back from frame '$b2', in real time from '$b1'"
    echo "crash $how: $((n - differ)) of $n frames identical to the real-time run's, the helper back from frame ${b2:-none}"
    [ "$fails" = 0 ] || sed 's/^/    /' "$d.log" | grep -v "^     *[0-9.]* s  frame"
done

# Repeated faults: chaos,mean=2 faults in every call from frame 29 on. The restarts back off
# (0.1, 0.2, 0.4, 0.8 s), the fifth fault in a row gives up with one line naming the plugin,
# and the run still ends with exit 0 and every frame, the face as it was (the frames after
# the give-up all equal).
mkdir -p "$tmp/giveup"
"$fp" run --plugin-dir "$tmp/pc" --mesh "$mesh" --input "replay:$rec,loop=1" --duration 20 \
    --mapping chaos,mean=2 --isolate-deadline "$deadline" --frames-out "$tmp/giveup" >"$tmp/giveup.log" 2>&1
rc=$?
[ "$rc" = 0 ] || fail "give-up: exit $rc, wanted 0"
waits=$(grep -o "restarts in [0-9.]* s (fault [0-9] in a row)" "$tmp/giveup.log" | sed 's/restarts in \([0-9.]*\) s.*/\1/' | tr '\n' ' ')
[ "$waits" = "0.1 0.2 0.4 0.8 " ] || fail "give-up: the restarts waited '$waits', wanted 0.1 0.2 0.4 0.8"
gave=$(grep -c "mapping 'chaos': isolated: .* 5 faults in a row: given up, the face stays as it was" "$tmp/giveup.log")
[ "$gave" = 1 ] || fail "give-up: said $gave times, wanted once"
ng=$(sed -n 's/^frames \([0-9]*\),.*/\1/p' "$tmp/giveup.log")
[ "$(ls "$tmp/giveup"/frame_*.obj | wc -l)" = "${ng:-x}" ] || fail "give-up: not every frame written"
last=$(frame "$tmp/giveup" $((ng - 1)))
k=$((ng - 60))
while [ "$k" -lt "$ng" ]; do
    cmp -s "$(frame "$tmp/giveup" "$k")" "$last" || { fail "give-up: frame $k moved after the give-up"; break; }
    k=$((k + 1))
done
echo "give-up: restarts waited $waits s, given up once, $ng frames, the last 60 still"
if [ "$fails" != 0 ]; then grep -v "^     *[0-9.]* s  frame" "$tmp/giveup.log" | sed 's/^/    /'; fi

# A bad key is refused by the isolated plugin's create as in process: exit 64, named.
"$fp" run --plugin-dir "$tmp/pc" --mesh "$mesh" --input "replay:$rec" --mapping steady,gain=7 \
    -o "$tmp/bad.obj" >"$tmp/bad.log" 2>&1
rc=$?
[ "$rc" = 64 ] || fail "bad key: exit $rc, wanted 64"
grep -q "gain" "$tmp/bad.log" || fail "bad key: the message does not name it"

# Usage: a mode that is none of the three, a deadline out of range (exit 64, named).
"$fp" run --isolate some --mesh "$mesh" --input "replay:$rec" >"$tmp/u1.log" 2>&1
rc=$?
[ "$rc" = 64 ] && grep -q -- "--isolate must be all, none or third-party, got 'some'" "$tmp/u1.log" ||
    fail "--isolate some: exit $rc: $(cat "$tmp/u1.log")"
"$fp" run --isolate-deadline 0 --mesh "$mesh" --input "replay:$rec" >"$tmp/u2.log" 2>&1
rc=$?
[ "$rc" = 64 ] && grep -q -- "--isolate-deadline must be 1 to 60000 ms, got '0'" "$tmp/u2.log" ||
    fail "--isolate-deadline 0: exit $rc: $(cat "$tmp/u2.log")"

# Bit-identical: --isolate all and none, the built-in mappings in turn.
i=0 same=0
for face in ict-facekit/generic_neutral_mesh.obj lee-perry-smith/LeePerrySmith.obj \
            mediapipe-canonical/canonical_face_model.obj; do
    for r in grab three-claps HandSplay-110fps Waiting-110fps; do
        case $((i % 3)) in 0) m=anchored ;; 1) m=unanchored ;; 2) m=onehand ;; esac
        i=$((i + 1))
        for iso in none all; do
            "$fp" run -q --isolate $iso --isolate-deadline 60000 --mapping $m --mesh "$data/faces/$face" \
                --input "replay:$data/hands/leap-motion/${r}_joints_mm.csv" --duration 1 \
                -o "$tmp/id-$iso.obj" --export "$tmp/id-$iso.pc2" --force >"$tmp/id-$iso.log" 2>&1 ||
                fail "$face $r $m --isolate $iso: exit $?"
        done
        if cmp -s "$tmp/id-none.pc2" "$tmp/id-all.pc2" && cmp -s "$tmp/id-none.obj" "$tmp/id-all.obj"; then
            same=$((same + 1))
        else
            fail "$face $r $m: --isolate all differs from in process"
        fi
        grep -q "isolated:" "$tmp/id-all.log" && fail "$face $r $m: a fault in the isolated run"
    done
done
echo "identical: $same of $i runs (3 faces x 4 recordings; anchored, unanchored, onehand in turn)"
# The base's copy follows the commits: map-steady,commit=1 reads its start points from the
# frame's mesh->base and commits every step.
for face in ict-facekit/generic_neutral_mesh.obj lee-perry-smith/LeePerrySmith.obj \
            mediapipe-canonical/canonical_face_model.obj; do
    for iso in none all; do
        "$fp" run -q --isolate $iso --isolate-deadline 60000 --plugin-dir "$tmp/pc" --mapping steady,commit=1 \
            --mesh "$data/faces/$face" --input "replay:$data/hands/leap-motion/HandSplay-110fps_joints_mm.csv" \
            --duration 2 -o "$tmp/cb-$iso.obj" --export "$tmp/cb-$iso.pc2" --force >"$tmp/cb-$iso.log" 2>&1 ||
            fail "$face steady,commit=1 --isolate $iso: exit $?"
    done
    committed=$(sed -n 's/^frames [0-9]*, deforming [0-9]*, engaged [0-9]*, committed \([0-9]*\).*/\1/p' "$tmp/cb-all.log")
    [ "${committed:-0}" -gt 0 ] || fail "$face steady,commit=1: nothing committed"
    cmp -s "$tmp/cb-none.pc2" "$tmp/cb-all.pc2" && cmp -s "$tmp/cb-none.obj" "$tmp/cb-all.obj" ||
        fail "$face steady,commit=1: --isolate all differs from in process (the base's copy)"
    echo "base copy: $face, $committed frames committed, isolated identical to in process"
done
[ "$fails" = 0 ] && echo "all passed" || { echo "$fails failed"; exit 1; }
