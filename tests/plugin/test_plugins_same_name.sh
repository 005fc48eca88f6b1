#!/bin/sh
# `facepuppet plugins` with a user's copy of a bundled plugin: two files giving the same
# factory name are told apart by their file and by what --input takes to load each, and a
# warning names both files and the one `--input NAME` loads. Before: both listed as 'replay'
# with nothing said, and --json's "name" the same for both.
# Usage: test_plugins_same_name.sh FACEPUPPET BUILTIN_DIR   (from the source root)
set -u
fp=$1 builtin=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
mine=$tmp/mine
mkdir "$mine" && chmod 700 "$mine" "$tmp"
cp "$builtin/input-replay.so" "$mine/input-myreplay.so"   # a copy under its own file name
cp "$builtin/input-replay.so" "$mine/input-replay.so"     # a copy shadowed by the built-in one
chmod 644 "$mine"/*.so

"$fp" plugins --plugin-dir "$mine" >"$tmp/out" 2>"$tmp/err" || fail "plugins exited $?"
cat "$tmp/err"
n=$(grep -Ec '^input +replay ' "$tmp/out")
[ "$n" = 3 ] || fail "$n entries named replay (3 files give it)"
grep -Fq "$mine/input-myreplay.so  (--input myreplay)" "$tmp/out" && echo "ok: the copy's file and load name" ||
    fail "the copy is not listed with its file and '--input myreplay'"
grep -Fq "$mine/input-replay.so  (--input $mine/input-replay.so)" "$tmp/out" && echo "ok: the shadowed copy loads by path" ||
    fail "the shadowed copy is not listed with '--input' and its path"
grep -Eq "/input-replay.so  \(--input replay\)$" "$tmp/out" && echo "ok: the built-in one loads by name" ||
    fail "the built-in replay is not listed with '--input replay'"
grep -Fq "warning: 3 input plugin files give the name 'replay'" "$tmp/err" || fail "no warning for the three files"
w=$(grep -F "give the name 'replay'" "$tmp/err")
for f in "$mine/input-myreplay.so" "$mine/input-replay.so"; do
    echo "$w" | grep -Fq "$f" || fail "the warning does not name $f"
done
echo "$w" | grep -Eq '`--input replay` loads [^ ]*/input-replay.so;' && ! echo "$w" | grep -Fq "loads $mine/" &&
    echo "ok: the warning says which one --input replay loads" || fail "the warning does not say the built-in one loads"
[ "$(grep -c "give the name" "$tmp/err")" = 1 ] || fail "not one warning line (each other name is given once)"

"$fp" plugins --json --plugin-dir "$mine" >"$tmp/json" 2>"$tmp/jerr" || fail "plugins --json exited $?"
python3 - "$tmp/json" "$mine" <<'PY' && echo "ok: --json tells the files apart" || fail "--json content"
import json, sys
d = json.load(open(sys.argv[1]))
mine = sys.argv[2]
reps = [p for p in d['plugins'] if p['name'] == 'replay']
assert len(reps) == 3, reps
by_file = {p['file']: p for p in reps}
assert by_file[mine + '/input-myreplay.so']['load'] == 'myreplay'
assert by_file[mine + '/input-replay.so']['load'] == mine + '/input-replay.so'
groups = [g for g in d['same_name'] if g['name'] == 'replay']
assert len(groups) == 1 and groups[0]['kind'] == 'input' and len(groups[0]['files']) == 3, d['same_name']
assert groups[0]['loads'].endswith('/input-replay.so') and not groups[0]['loads'].startswith(mine), groups[0]
assert by_file[groups[0]['loads']]['load'] == 'replay'
assert "give the name 'replay'" in groups[0]['warning'] and groups[0]['loads'] in groups[0]['warning']
PY
[ -s "$tmp/jerr" ] && { fail "--json: stderr not empty (its warning belongs in the document)"; cat "$tmp/jerr"; }
[ $fails = 0 ] && echo PASS || { echo "$fails failure(s)"; exit 1; }
