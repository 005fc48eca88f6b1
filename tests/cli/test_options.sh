#!/usr/bin/env bash
# One set of names across commands (issue 53, item 5): -P is --plugin-dir wherever a command
# takes plugin folders (run, live, play, export, calibrate, monitor, plugins); usage lines
# say SPEC for --mapping; export resamples with --resample (--fps kept as its older name),
# while run's --fps is the session's rate. Each -P is checked by effect: a plugin folder
# given only with -P is searched (a missing folder is named, or its plugins are listed).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$(cd "$build" && pwd)/bin/facepuppet"
plugdir="$(cd "$build" && pwd)/lib/facepuppet"
data=$(cd "${FP_SHARED_DATA:-../shared/data}" && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-options-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
cd "$tmp" || exit 1

# -P reaches the plugin search: `plugins -P DIR --json` lists DIR's plugins under DIR
"$fp" plugins -P "$plugdir" --json >p.json 2>p.err || { cat p.err; fail "plugins -P exited $?"; }
grep -q "$plugdir" p.json || fail "plugins -P $plugdir: the folder is not in the listing"
# every command that takes plugin folders accepts -P (getopt would say 'invalid option')
for c in run live play export calibrate monitor plugins; do
    "$fp" $c -P /nonexistent-plugin-dir --help >h.out 2>&1
    grep -qi "invalid option\|unrecognized option" h.out && { cat h.out; fail "$c: -P refused"; }
    "$fp" $c --help 2>&1 | grep -q -- "-P, --plugin-dir" || fail "$c --help does not show -P, --plugin-dir"
done
# usage lines say SPEC for a mapping
for c in run live bench; do
    "$fp" $c --help 2>&1 | grep -q -- "--mapping NAME" && fail "$c --help says --mapping NAME (a SPEC)"
done
# export: --resample is the rate of the exported samples; --fps is the same (older name)
"$fp" run --mesh "$data/faces/ict-facekit/generic_neutral_mesh.obj" \
    --input "replay:$data/hands/leap-motion/three-claps_joints_mm.csv,fast=1" --duration 0.5 \
    --take-dir takes --slate opt -q -o run.obj >/dev/null 2>&1 || fail "run exited $?"
take=takes/opt_T001.fptake
"$fp" export "$take" --format pc2 --resample 24 --out a.pc2 >a.out 2>&1 || { cat a.out; fail "export --resample exited $?"; }
grep -q "24 fps" a.out || { cat a.out; fail "export --resample 24: the line does not say 24 fps"; }
"$fp" export "$take" --format pc2 --fps 24 --out b.pc2 >b.out 2>&1 || { cat b.out; fail "export --fps exited $?"; }
cmp -s a.pc2 b.pc2 || fail "export --fps 24 and --resample 24 differ"
"$fp" export "$take" --format pc2 --resample 0 --out c.pc2 >c.out 2>&1
[ $? -eq 64 ] || fail "export --resample 0: want exit 64"
grep -q -- "--resample" c.out || fail "export --resample 0: the message does not name --resample"
# `facepuppet help CMD` (the top --help offers it) is `facepuppet CMD --help`, exit 0, for
# every command listed there; an unknown CMD is usage (64); no arguments is usage (64).
cmds=$("$fp" --help | sed -n '/^Commands:/,/^$/p' | awk 'NF>1 {print $1}')
[ -n "$cmds" ] || fail "facepuppet --help lists no commands"
for c in $cmds; do
    "$fp" $c --help >want.out 2>&1; want=$?
    "$fp" help $c >got.out 2>&1; got=$?
    [ $want -eq 0 ] || fail "$c --help exited $want"
    [ $got -eq 0 ] || fail "help $c exited $got"
    cmp -s want.out got.out || { diff want.out got.out | head; fail "help $c differs from $c --help"; }
done
# an unknown option is usage (64), said as "facepuppet CMD: ..." (getopt's message named the
# command alone: "run: unrecognized option")
for c in $cmds; do
    "$fp" $c --no-such-option-xyz >o.out 2>&1; rc=$?
    [ $rc -eq 64 ] || { cat o.out; fail "$c --no-such-option-xyz: exit $rc, want 64"; }
    head -1 o.out | grep -q "^facepuppet $c: " || { cat o.out; fail "$c: the message does not start 'facepuppet $c: '"; }
done
# a long option is spelled out: getopt_long's unambiguous prefix was taken silently (`run
# --frames 30` was --frames-out 30 and wrote 225 OBJ files into ./30); now usage (64) naming
# the token and the option it abbreviates, nothing written, in every command's parser
"$fp" run --frames 30 --duration 0.2 >o.out 2>&1; rc=$?
[ $rc -eq 64 ] || { cat o.out; fail "run --frames 30: exit $rc, want 64"; }
grep -q "^facepuppet run: unknown option '--frames' (did you mean --frames-out?)" o.out \
    || { cat o.out; fail "run --frames: the message"; }
[ -e 30 ] && fail "run --frames 30 wrote ./30"
"$fp" run --frames=30 >o.out 2>&1; rc=$?
[ $rc -eq 64 ] && grep -q "unknown option '--frames' (did you mean --frames-out?)" o.out \
    || { cat o.out; fail "run --frames=30: exit $rc"; }
for v in "plugins --js" "plugins check --js x.so" "takes rate --hel" "export --form pc2 x.fptake" \
         "bench --hel" "pose --mes x.obj"; do
    "$fp" $v >o.out 2>&1; rc=$?
    c=${v%% --*}
    [ $rc -eq 64 ] || { cat o.out; fail "$v: exit $rc, want 64"; }
    head -1 o.out | grep -q "^facepuppet $c: unknown option '--" || { cat o.out; fail "$v: the message"; }
done
# ... while the full names, with a separate value or =VALUE, still work
"$fp" plugins --json -P "$plugdir" >o.out 2>&1 || { cat o.out; fail "plugins --json refused"; }
"$fp" export "$take" --format=pc2 --out=d.pc2 >o.out 2>&1 || { cat o.out; fail "export --format=pc2 refused"; }
# bench's values: a missing one is named (was "unknown option '--case'"), levels are digits
"$fp" bench --case >o.out 2>&1; rc=$?
[ $rc -eq 64 ] && grep -q "'--case' requires an argument" o.out || { cat o.out; fail "bench --case: exit $rc"; }
for v in " 2" "2," "0x2" "+2" "4"; do
    "$fp" bench --subdivide "$v" --case nope >o.out 2>&1; rc=$?
    [ $rc -eq 64 ] && grep -q "subdivide '$v'" o.out || { cat o.out; fail "bench --subdivide '$v': exit $rc"; }
done
for v in "takes rate" "takes describe" "plugins check"; do
    "$fp" $v --no-such-option-xyz >o.out 2>&1; rc=$?
    [ $rc -eq 64 ] || { cat o.out; fail "$v --no-such-option-xyz: exit $rc, want 64"; }
    head -1 o.out | grep -q "^facepuppet $v: " || { cat o.out; fail "$v: the message does not start 'facepuppet $v: '"; }
done
# live names a bad file argument before it opens its window: without a display it said "no
# display" (exit 66 too) and never the file. --mesh, --rig and a replay: input's FILE, as run.
if "$fp" live --help >/dev/null 2>&1; then
    for a in "--mesh nope.obj" "--rig nope.json" "--input replay:nope.csv"; do
        env -u DISPLAY -u WAYLAND_DISPLAY "$fp" live $a >l.out 2>&1; rc=$?
        [ $rc -eq 66 ] || { cat l.out; fail "live $a: exit $rc, want 66"; }
        head -1 l.out | grep -q "^facepuppet live: .*nope\.[a-z]*: cannot open: No such file" ||
            { cat l.out; fail "live $a: the first line does not name the file"; }
        grep -qi "display" l.out && { cat l.out; fail "live $a: a display was tried first"; }
    done
fi
"$fp" help frob >u.out 2>&1
[ $? -eq 64 ] || fail "help frob: want exit 64"
grep -q "frob" u.out || fail "help frob: the message does not name frob"
"$fp" >n.out 2>&1
[ $? -eq 64 ] || fail "facepuppet with no arguments: want exit 64"
echo ok
