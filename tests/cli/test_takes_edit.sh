#!/usr/bin/env bash
# takes rate and takes describe (issue 53, item 7), with the facepuppet command: the header
# rewritten (what `takes`, `takes --json`, `info` and `play` report changes), every byte after
# the header chunk as it was, the frames play as before; the refusals (a rating outside 0..5,
# a missing take, usage) exit as documented and leave the take byte for byte as it was.
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$(cd "$build" && pwd)/bin/facepuppet"
pd=(--plugin-dir "$(cd "$build" && pwd)/lib/facepuppet")
data=$(cd "${FP_SHARED_DATA:-../shared/data}" && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-takes-edit-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
expect() { local want=$1; shift; "$@" >"$tmp/x.out" 2>&1; local got=$?
           [ $got -eq "$want" ] || { cat "$tmp/x.out"; fail "exit $got, want $want: $*"; }; }
cd "$tmp" || exit 1
"$fp" run "${pd[@]}" --mesh "$data/faces/ict-facekit/generic_neutral_mesh.obj" \
    --input "replay:$data/hands/leap-motion/three-claps_joints_mm.csv,fast=1" --duration 0.4 \
    --take-dir takes --slate clap -q -o run.obj >/dev/null 2>&1 || fail "run exited $?"
take=takes/clap_T001.fptake
cp "$take" orig.fptake
expect 0 "$fp" play "${pd[@]}" "$take" -o before.obj
grep -q "rated" "$tmp/x.out" && fail "play reports a rating before one was set"

# rate: takes --json, the table and play report it
expect 0 "$fp" takes rate "$take" 4
grep -q "rating 4/5" "$tmp/x.out" || { cat "$tmp/x.out"; fail "takes rate did not say the rating"; }
"$fp" takes --json takes >takes.json || fail "takes --json exited $?"
python3 -c "import json,sys; t=json.load(open(sys.argv[1])); assert t[0]['rating']==4 and t[0]['description']=='', t" takes.json ||
    fail "takes --json: rating 4 not reported"
"$fp" takes takes | grep -Eq "^clap +1 .* 4/5 +anchored .* ok +-$" || { "$fp" takes takes; fail "the table's rating"; }
expect 0 "$fp" play "${pd[@]}" "$take" -o after.obj --force
grep -q "(clap take 1, rated 4/5, " "$tmp/x.out" || { cat "$tmp/x.out"; fail "play does not report the rating"; }
cmp -s before.obj after.obj || fail "play's frames changed after takes rate"

# describe: shown by takes (table and JSON), info, play
desc='kept: "the big clap"	(tab) é'
expect 0 "$fp" takes describe takes/clap_T001 "$desc"   # (the .fptake may be left out)
"$fp" takes --json takes >takes.json || fail "takes --json exited $?"
python3 - "$desc" takes.json <<'PY' || fail "takes --json: the description"
import json, sys
t = json.load(open(sys.argv[2]))
assert t[0]['description'] == sys.argv[1] and t[0]['rating'] == 4, t
PY
"$fp" takes takes | grep -q 'ok          kept: "the big clap" (tab) é$' || { "$fp" takes takes; fail "the table's description"; }
"$fp" info "$take" | grep -q 'description  kept: "the big clap"' || fail "info: no description"
expect 0 "$fp" play "${pd[@]}" "$take"
grep -qF '(clap take 1, rated 4/5, "kept: "the big clap"' "$tmp/x.out" || { cat "$tmp/x.out"; fail "play: no description"; }

# every byte after the header chunk as it was; the header's other members as written
python3 - orig.fptake "$take" <<'PY' || fail "the take's bytes outside the rating and description changed"
import json, struct, sys
a, b = (open(p, 'rb').read() for p in sys.argv[1:3])
la, lb = (struct.unpack_from('<I', x, 24)[0] for x in (a, b))
assert a[:16] == b[:16] and a[28:32] == b[28:32], "signature or record count"
assert a[36 + la:] == b[36 + lb:], "frames or end chunk"
ha, hb = json.loads(a[32:32 + la]), json.loads(b[32:32 + lb])
assert hb['rating'] == 4 and ha['rating'] == 0
for h in (ha, hb):
    del h['rating'], h['description']
assert ha == hb, (ha, hb)
PY

# refusals: exit status, message, the take unchanged
cp "$take" kept.fptake
expect 64 "$fp" takes rate "$take" 6
grep -q "N must be a whole number 0..5" "$tmp/x.out" || { cat "$tmp/x.out"; fail "rate 6"; }
expect 64 "$fp" takes rate "$take"
expect 64 "$fp" takes describe "$take" two words
expect 66 "$fp" takes rate takes/nope.fptake 3
echo "not a take" >takes/junk.fptake
expect 65 "$fp" takes rate takes/junk.fptake 3
cmp -s "$take" kept.fptake || fail "a refused edit changed the take"
# a take with no end chunk (its recorder killed): refused (73) pointing at --force; the
# --force given after TAKE N as the message suggests rewrites it (before: 64, "give TAKE N")
head -c 2000 "$take" >takes/open_T001.fptake
expect 73 "$fp" takes rate takes/open_T001.fptake 3
grep -q "(--force rewrites it anyway)" "$tmp/x.out" || { cat "$tmp/x.out"; fail "open take: no hint of --force"; }
expect 0 "$fp" takes rate takes/open_T001.fptake 3 --force
expect 0 "$fp" takes describe takes/open_T001.fptake "cut short" --force
"$fp" info takes/open_T001.fptake 2>/dev/null | grep -q "rating       3/5" || fail "rate --force after N: no rating"
"$fp" info takes/open_T001.fptake 2>/dev/null | grep -q "description  cut short" || fail "describe --force after TEXT"
expect 0 "$fp" takes describe "$take" "--force"   # a TEXT alone is a TEXT
"$fp" info "$take" | grep -q "description  --force" || fail "describe TAKE --force: not the text"
# 0 clears the rating, "" the description
expect 0 "$fp" takes rate "$take" 0
expect 0 "$fp" takes describe "$take" ""
"$fp" info "$take" | grep -q "rating       0/5" || fail "rate 0 did not clear the rating"
"$fp" info "$take" | grep -q "description" && fail "describe \"\" did not clear the description"
"$fp" takes --help | grep -q "takes rate TAKE N" || fail "takes --help: no rate"
echo "PASS"
