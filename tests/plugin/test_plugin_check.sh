#!/bin/sh
# `facepuppet plugins check` passes every built-in plugin and fails each fixture plugin with a
# message naming the cause; `facepuppet run` names the mapping at fault (overrun: exit 78,
# segfault: the fatal-signal line with the frame, slow process: its time; an engine error
# on every frame: one line and its count); `plugins` lists.
# Usage: test_plugin_check.sh FACEPUPPET FIXTURE_DIR BUILTIN_DIR   (from the source root)
set -u
fp=$1 fx=$2 builtin=$3
data=${FP_SHARED_DATA:-../shared/data}
rec=$data/hands/leap-motion/three-claps_joints_mm.csv
mesh=$data/faces/ict-facekit/generic_neutral_mesh.obj
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# expect RC PATTERN CMD...: CMD exits RC and its output matches PATTERN (grep -E).
expect() {
    want=$1 pat=$2
    shift 2
    "$@" >"$tmp/out" 2>&1
    rc=$?
    if [ "$rc" != "$want" ]; then fail "$* exited $rc, wanted $want"; sed 's/^/    /' "$tmp/out"; return; fi
    if ! grep -Eq -- "$pat" "$tmp/out"; then fail "$*: no '$pat' in:"; sed 's/^/    /' "$tmp/out"; return; fi
    echo "ok: $* -> $rc, '$pat'"
}

# Built-in plugins pass (the glove has no device here: a documented skip, exit 0).
expect 0 'passed: 17 checks' "$fp" plugins check "$builtin/map-anchored.so"  # 17: a check per key (engage, points, widen, apart)
expect 0 'PASS  determinism +after reset the same 320 frames' "$fp" plugins check "$builtin/map-unanchored.so"
# ABI 1.3 mappings also get 80 frames with 1 and 3 further performers' hands (extra_hands)
for m in anchored unanchored onehand; do
    expect 0 'PASS  performers +80 frames with 1 and 3 further performers' "$fp" plugins check "$builtin/map-$m.so"
done
expect 0 'PASS  events +[0-9]+ events well-formed' "$fp" plugins check "$builtin/input-replay.so" --arg "$rec"
# fast=1 (the help's own example): a recording's events run ahead of the host clock, on its own
expect 0 'PASS  events +[0-9]+ events well-formed' "$fp" plugins check "$builtin/input-replay.so" --arg "$rec" --key fast=1
# a FIFO given as the plugin, or named like one in a plugin folder: refused, never waited on
# (dlopen would wait for a writer; timeout's 124 where it did)
mkfifo "$tmp/fifo.so"
expect 78 'fifo.so: cannot load: not a regular file' timeout 30 "$fp" plugins check "$tmp/fifo.so"
mkdir "$tmp/fifodir" && mkfifo "$tmp/fifodir/input-fifo.so"
expect 0 'input-fifo.so: cannot load: not a regular file' timeout 30 "$fp" plugins --plugin-dir "$tmp/fifodir"
# ... and one of the same name in a later folder: the FIFO shadows it, looked at without opening
mkdir "$tmp/fifodir2" && cp "$builtin/input-replay.so" "$tmp/fifodir2/input-fifo.so"
expect 0 'input-fifo.so: cannot load: not a regular file' timeout 30 "$fp" plugins --plugin-dir "$tmp/fifodir" --plugin-dir "$tmp/fifodir2"
# ... and a mapping named by one, which run loads in a helper process (not one of ours): the
# host opened the file to keep it for restarts and waited there for a writer (124, no output)
mkfifo "$tmp/fifodir/map-fifo.so"
expect 78 "mapping 'fifo': .*map-fifo.so: cannot load: not a regular file" timeout 30 "$fp" run -q \
    --plugin-dir "$tmp/fifodir" --mapping fifo --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" \
    --input "replay:$rec,fast=1" --duration 0.2 --out "$tmp/fifo.obj"
[ -e "$tmp/fifo.obj" ] && fail "run --mapping fifo wrote $tmp/fifo.obj"
# a plugin file cut short (a copy interrupted): its headers whole, its segments past the
# end. dlopen mapped them and the first touch past the end was SIGBUS, taking the listing
# (and a run with it as an input, loaded in process) down with "not inside a plugin"
mkdir "$tmp/cut" && head -c 3000 "$builtin/input-replay.so" >"$tmp/cut/input-cut.so"
expect 0 'input-cut.so: cannot load: cut short: .* ends at byte [0-9]+ of a file of 3000 bytes' \
    timeout 30 "$fp" plugins --plugin-dir "$tmp/cut"
expect 78 "input-cut.so: cannot load: cut short" timeout 30 "$fp" run -q --plugin-dir "$tmp/cut" \
    --input cut:x --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" --out "$tmp/cut.obj"
# a recording given with --arg that is not there: a failure, not a device to skip
expect 1 'FAIL  create .*No such file' "$fp" plugins check "$builtin/input-replay.so" --arg /nonexistent/rec.csv
expect 0 'PASS  cycle +5 x create' "$fp" plugins check "$builtin/input-pedal.so"
expect 0 'SKIP  start +needs a device: .*cannot open /nonexistent/glove' \
    "$fp" plugins check "$builtin/input-cyberglove.so" --arg /nonexistent/glove
expect 0 '"passed":[[:space:]]+true' "$fp" plugins check "$builtin/map-anchored.so" --json
# A replay without its recording fails cleanly, naming what is missing.
expect 1 'FAIL  create .*replay' "$fp" plugins check "$builtin/input-replay.so"
# osc and take declare their keys (ABI 1.1 params): each key's range is checked against what
# create refuses (osc on a free port; take on a take recorded here).
expect 0 'passed: 15 checks' "$fp" plugins check "$builtin/input-osc.so" --arg 0  # 9 range checks
"$fp" run -q --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" \
    --input "replay:$rec,fast=1" --duration 0.5 --out "$tmp/t.obj" --take-dir "$tmp/takes" \
    --slate chk >/dev/null 2>&1 || fail "recording a take for the take input's check"
expect 0 'passed: 9 checks' "$fp" plugins check "$builtin/input-take.so" \
    --arg "$tmp/takes/chk_T001.fptake"

# Each broken fixture fails with a message naming the cause.
expect 0 'passed' "$fp" plugins check "$fx/map-fixture.so"
# Not one of facepuppet's own: its frames again in a helper process (issue 56), identical;
# --isolate none leaves that pass out, --isolate all adds it for a built-in mapping.
expect 0 'PASS  isolated +in a helper process the same 240 frames gave identical control sets' \
    "$fp" plugins check "$fx/map-fixture.so"
expect 0 'passed: 9 checks' "$fp" plugins check "$fx/map-fixture.so" --isolate none  # 10 with the isolated pass
# map-fixture declares ABI 1.0: no frames with further performers, said so
expect 0 'INFO  performers +the plugin declares ABI 1\.0, before 1\.3: no frames with further performers' \
    "$fp" plugins check "$fx/map-fixture.so" --isolate none
# the isolated pass carries the further performers' hands (isolate_shm.h): the same 320 frames
expect 0 'PASS  isolated +in a helper process the same 320 frames gave identical control sets' \
    "$fp" plugins check "$builtin/map-unanchored.so" --isolate all
expect 0 'PASS  isolated' "$fp" plugins check "$builtin/map-onehand.so" --isolate all
# A mapping written in C++ with FP_PLUGIN_DECLARE_ENTRY loads (before: no entry symbol, 78)
expect 0 "PASS  load +mapping plugin 'cxx'" "$fp" plugins check "$fx/map-fixture-cxx.so"
expect 1 "FAIL  overrun +wrote past the capacity of the host's start array" "$fp" plugins check "$fx/map-fixture-overrun.so"
expect 1 'FAIL  finite points +control vector 0: end point .*nan.* is not finite' "$fp" plugins check "$fx/map-fixture-nan.so"
# ABI 1.3: a mapping that writes into the host's const extra_hands, or reads further hands past
# the extra_performers given (the host's rows after them hold NaN), fails on such a frame
expect 1 "FAIL  performers +wrote into the host's extra_hands\[0\] .*\(first on frame [0-9]+, 1 further performer, hands far\)" \
    "$fp" plugins check "$fx/map-fixture-extrawrite.so"
expect 1 'FAIL  finite points +control vector [0-9]+: start point .*read past them\?\) \(first on frame [0-9]+, 1 further performer' \
    "$fp" plugins check "$fx/map-fixture-extraread.so"
expect 1 'FAIL  time +process took [0-9]+\.[0-9]+ ms .*over the budget of 2 ms' "$fp" plugins check "$fx/map-fixture-slow.so"
expect 1 'FAIL  create +create returned 0 without an instance' "$fp" plugins check "$fx/map-fixture-noinstance.so"
expect 78 'FAIL  load .*built for plugin ABI 2\.0, this facepuppet has ABI 1\.3' "$fp" plugins check "$fx/map-fixture-abi2.so"
expect 78 'built for plugin ABI 2\.0' "$fp" plugins check "$fx/input-fixture-abi2.so"
# a factory offered but broken is said so (before: "offers no mapping factory", as if none)
expect 78 "map-fixture-noname.so: its mapping factory \('facepuppet.mapping-factory/1'\) has no name" \
    "$fp" plugins check "$fx/map-fixture-noname.so"
expect 78 "map-fixture-noname.so: its mapping factory .* has no name" \
    "$fp" run --isolate none --plugin-dir "$fx" --mesh "$mesh" --input "replay:$rec" --duration 1 -o "$tmp/out.obj" --force --mapping fixture-noname
expect 64 'give one FILE' "$fp" plugins check
# A plugin that crashes, calls exit() or hangs in a call fails the check (exit 1, a FAIL line
# naming the signal, the exit or the hang, and the call and frame), the checker itself intact:
# the checks run in a child process (before: 139, 134, exit 0 with no verdict, a hang)
expect 1 'FAIL  process +the plugin died of SIGSEGV during process \(frame 3\)' \
    timeout 60 "$fp" plugins check "$fx/map-fixture-segv.so"
expect 1 'FAIL  create +the plugin died of SIGABRT during create' timeout 60 "$fp" plugins check "$fx/map-fixture-abort.so"
expect 1 'FAIL  process +the plugin ended the process with exit status 0 during process \(frame 3\), without a verdict' \
    timeout 60 "$fp" plugins check "$fx/map-fixture-exit.so"
expect 1 'FAIL  process +no progress for 2 s during process \(frame 29\): the plugin hangs' \
    timeout 60 "$fp" plugins check "$fx/map-fixture-spin.so" --deadline 2
expect 1 'FAILED: .*map-fixture-spin.so: 1 check\(s\) failed' timeout 60 "$fp" plugins check "$fx/map-fixture-spin.so" --deadline 2
# An input's event over sizeof(fp_event), pushed again while push_event answers false (as a
# pacer does): named with its size and the limit, as the host refuses it (before: false, the
# plugin pushed it again for good and the check failed it as a hang)
expect 1 'FAIL  events +3 push_event calls with a size no event has \(the first: joint angles, header.type 1, of [0-9]+ bytes; the host takes [0-9]+ to [0-9]+' \
    timeout 60 "$fp" plugins check "$fx/input-fixture.so" --key oversize=3 --key oversize_retry=1 --deadline 2 --cycles 1
# ... in --json too: one document, the failure among its checks; a plugin's stdout (in process
# and in the isolated pass's helper) goes to stderr, not into the document
for f in segv print; do
    timeout 60 "$fp" plugins check "$fx/map-fixture-$f.so" --json >"$tmp/$f.json" 2>"$tmp/$f.err"
    echo $? >"$tmp/$f.rc"
done
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); \
assert d['passed'] is False and any(c['result']=='fail' and 'SIGSEGV during process (frame 3)' in c['message'] for c in d['checks'])" \
    "$tmp/segv.json" && [ "$(cat "$tmp/segv.rc")" = 1 ] && echo "ok: --json of a crashing plugin: exit 1, the failure listed" ||
    { fail "--json of a crashing plugin (exit $(cat "$tmp/segv.rc"))"; sed 's/^/    /' "$tmp/segv.json"; }
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d['passed'] is True" "$tmp/print.json" &&
    grep -q 'fixture-print: stdout of process' "$tmp/print.err" && echo "ok: a printing plugin's --json parses, its text on stderr" ||
    { fail "--json of a printing plugin"; head -5 "$tmp/print.json" | sed 's/^/    /'; }

# The list: built-in plugins with their keys, broken fixtures with the reason, as text and JSON.
# (the fixtures that crash in init would end the listing, naming themselves: left out here)
mkdir "$tmp/list" && chmod 700 "$tmp/list"
for f in "$fx"/*.so; do case $f in *crash*|*hanginit*) ;; *) cp "$f" "$tmp/list/" ;; esac; done
chmod 644 "$tmp"/list/*.so
expect 0 'release +float +\[0\.1, 100\]' "$fp" plugins
expect 0 'fixture-abi2 +BROKEN \(abi\)' "$fp" plugins --plugin-dir "$tmp/list"
expect 0 '"status":[[:space:]]+"no-entry"' "$fp" plugins --json --plugin-dir "$tmp/list"
"$fp" plugins --json --plugin-dir "$tmp/list" >"$tmp/list.json" 2>&1
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); k={p['name']:p for p in d['plugins']}; \
assert k['anchored']['keys'][2]['name']=='release' and k['anchored']['abi']=='1.3'; \
assert k['replay']['keys'][0]['name']=='speed'; assert d['complete'] is True; assert k['fixture-initfails']['status']=='init-failed'" \
    "$tmp/list.json" && echo "ok: plugins --json parses" || fail "plugins --json content"
chmod 777 "$tmp" && expect 0 "skipped" "$fp" plugins --plugin-dir "$tmp"; chmod 700 "$tmp"
# A plugin whose init never returns ends the listing after 10 s, named, exit 78, what was
# listed kept (before: the listing hung without a word; timeout's 124)
mkdir "$tmp/hang" && chmod 700 "$tmp/hang" && cp "$fx/input-fixture-hanginit.so" "$tmp/hang/"
expect 78 "plugin '.*input-fixture-hanginit.so' has not returned from init for 10 s: it hangs" \
    timeout 60 "$fp" plugins --plugin-dir "$tmp/hang"
grep -Eq "^mapping +anchored " "$tmp/out" && echo "ok: the listing before it kept" || fail "the listing before the hang lost"
# ... and with --json, one JSON document still: what was listed, "complete": false and the
# hang as "error" (before: exit 78 and no document on stdout)
timeout 60 "$fp" plugins --json --plugin-dir "$tmp/hang" >"$tmp/hang.json" 2>"$tmp/hang.err"; rc=$?
[ "$rc" = 78 ] || fail "plugins --json with a hanging init exited $rc, wanted 78"
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); n=[p['name'] for p in d['plugins']]; \
assert 'anchored' in n, n; assert d['complete'] is False; assert 'hanginit.so' in d['error'] and 'hangs' in d['error']" \
    "$tmp/hang.json" && echo "ok: plugins --json with a hang prints its document" \
    || { fail "plugins --json with a hang: no valid document"; head -c 400 "$tmp/hang.json"; }

# run: the host names the mapping at fault.
run() { "$fp" run --isolate none --plugin-dir "$fx" --mesh "$mesh" --input "replay:$rec" --duration 1 --quiet -o "$tmp/out.obj" --force "$@"; }
expect 78 "mapping 'fixture-overrun': wrote past the capacity of the host's start array \(64 entries\) on frame [0-9]+; the mapping is stopped" run --mapping fixture-overrun
expect 139 "fatal signal SIGSEGV in plugin 'fixture-segv' during process \(frame 3\)" run --mapping fixture-segv
expect 0 "mapping 'fixture-slow': process took [0-9]+\.[0-9]+ ms on frame [0-9]+, over the budget of 2 ms" run --mapping fixture-slow
expect 0 "mapping 'fixture-nan': invalid control set: vector 0's end point \(.*nan.*\) is not finite .* on frame [0-9]+" run --mapping fixture-nan
# ... and a take of it plays: the refused sets are recorded emptied, not as the mapping wrote
# them (before: play read the NaN as damage, "no intact frame to play", 65)
expect 0 "mapping 'fixture-nan': invalid control set" run --mapping fixture-nan --take-dir "$tmp/nantakes"
"$fp" play --plugin-dir "$fx" "$(ls "$tmp"/nantakes/*.fptake | head -1)" -o "$tmp/nanplay.obj" --force >"$tmp/out" 2>&1
rc=$?
if [ $rc != 0 ] || grep -q "cut\|damage\|no intact" "$tmp/out"; then
    fail "the take of a refused mapping does not play whole (exit $rc)"; sed 's/^/    /' "$tmp/out"
else echo "ok: the take of a refused mapping plays (exit 0)"; fi
expect 78 "mapping 'fixture-noinstance': create returned 0 without an instance" run --mapping fixture-noinstance
# an instance without process() (a mapping) or start() (an input) is refused in process as
# isolated and by plugins check: exit 78, named (before: called through NULL, exit 139)
expect 78 "mapping 'fixture-noprocess': the fp_mapping has size [0-9]+ or no process\(\)" run --mapping fixture-noprocess
expect 78 "input 'fixture,nostart=1': the fp_input has size [0-9]+, or no start\(\)" \
    "$fp" run --isolate none --plugin-dir "$fx" --mesh "$mesh" --duration 1 -o "$tmp/out.obj" --force --input fixture,nostart=1
# A SPEC whose NAME holds a '/' names the plugin's file (docs/plugin-guide.md), in process
# and isolated (before: "bad name", exit 64), an input's too.
expect 0 "frames [0-9]+, deforming" run --mapping "$fx/map-fixture.so"
# (a deadline of 500 ms, not the default 50: under the sanitizers the helper's SIGSEGV report
# takes longer than 50 ms, and the host then kills it for the deadline first; there ASan ends
# the helper with exit status 1, not the signal: there both are accepted, as test_isolate.sh does)
died="died of SIGSEGV"
[ "${FP_TEST_TIME_SCALE:-1}" -gt 1 ] && died="(died of SIGSEGV|exited with status [0-9]+)"
expect 0 "isolated: the helper process $died during process \(frame 3\)" \
    "$fp" run --plugin-dir "$fx" --mesh "$mesh" --input "replay:$rec" --duration 1 -o "$tmp/out.obj" --force \
    --isolate-deadline $((500 * ${FP_TEST_TIME_SCALE:-1})) --mapping "$fx/map-fixture-segv.so"
expect 0 "frames [0-9]+, deforming" "$fp" run --isolate none --plugin-dir "$fx" --mesh "$mesh" --duration 1 \
    --quiet -o "$tmp/out.obj" --force --mapping fixture --input "$builtin/input-replay.so:$rec"
# A radius the engine would refuse (1e20: finite and positive) is the mapping's error, named,
# on every frame: one line, then its count (before, the host passed it and the engine said
# "engine: invalid argument" without the mapping's name, and a take recorded the set).
expect 0 "mapping 'fixture-enginefail': invalid control set: radius 1e\+20 of an active set, outside \[1e-15, 1e\+15\] mesh units on frame 0; the base shown \(repeated [0-9]+ more times\)" run --mapping fixture-enginefail
n=$(grep -c "mapping 'fixture-enginefail': invalid control set" "$tmp/out")
[ "$n" = 2 ] && echo "ok: the repeated error: 2 lines" || { fail "error lines: $n, wanted 2"; sed 's/^/    /' "$tmp/out"; }
grep -q "engine: " "$tmp/out" && { fail "the engine saw the refused set"; sed 's/^/    /' "$tmp/out"; }
# An isolated mapping that writes past the arrays is stopped as in process: exit 78.
runi() { "$fp" run --plugin-dir "$fx" --mesh "$mesh" --input "replay:$rec" --duration 1 --quiet -o "$tmp/out.obj" --force "$@"; }
expect 78 "mapping 'fixture-overrun': wrote past the capacity of the host's arrays on frame [0-9]+ \(in its helper process\); the mapping is stopped" runi --mapping fixture-overrun
# ... and one that writes before its arrays (the shared set's capacity) and claims 10 million
# vectors: the host copies no more than its own capacity and refuses the set, named (before:
# it trusted the helper's capacity and crashed with SIGSEGV, ending the show)
expect 0 "mapping 'fixture-underwrite': control set over capacity: count 10000000 > capacity 64" runi --mapping fixture-underwrite
# A create that fills err to its very end (no NUL): the message is the plugin's bytes and
# nothing after them, in process and isolated (before: read past the buffer, stack garbage)
for iso in none third-party; do
    "$fp" run --isolate $iso --plugin-dir "$fx" --mesh "$mesh" --input "replay:$rec" --duration 1 -o "$tmp/out.obj" \
        --force --mapping fixture-errfill >"$tmp/out" 2>&1
    rc=$?
    if [ $rc = 64 ] && tail -1 "$tmp/out" | grep -Eq "^facepuppet run: mapping 'fixture-errfill': E{100,}$"; then
        echo "ok: errfill ($iso): exit 64, the plugin's bytes alone"
    else
        fail "errfill ($iso): exit $rc"; tail -1 "$tmp/out" | od -c | tail -4
    fi
done
# An isolated mapping's helper is the kernel's first choice when memory runs out (a plugin
# that eats memory without end must not take the host with it): oom_score_adj 1000 there
# (before: the host's, 0).
expect 0 "mapping 'fixture-oom': oom_score_adj 1000$" runi --mapping fixture-oom
# An isolated mapping that prints: its stdout is facepuppet's stderr (the helper's), so run's
# stdout holds the summary alone, which scripts parse (before: the plugin's lines mixed in).
runi --mapping fixture-print >"$tmp/print.out" 2>"$tmp/print.err"
rc=$?
if [ $rc = 0 ] && [ "$(wc -l <"$tmp/print.out")" = 1 ] && grep -q '^frames [0-9]*, ' "$tmp/print.out" &&
   grep -q 'fixture-print: stdout of create' "$tmp/print.err" && grep -q 'fixture-print: stdout of process' "$tmp/print.err"; then
    echo "ok: an isolated plugin's stdout on stderr, run's stdout the summary alone"
else
    fail "an isolated plugin's stdout (exit $rc): stdout:"; head -3 "$tmp/print.out" | sed 's/^/    /'
fi
# An isolated mapping whose create aborts: exit 78, named once, the call said (it died in create,
# not while loading; before: "mapping 'x': mapping 'x': ... died of SIGABRT while loading")
expect 78 "run: mapping 'fixture-abort': its helper process died of SIGABRT in the plugin's create$" runi --mapping fixture-abort
# Mapping log lines carry the instance's name.
expect 0 "facepuppet: mapping 'fixture': fixture A created" run --mapping fixture

echo "$fails failure(s)"
[ "$fails" = 0 ]
