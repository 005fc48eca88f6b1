#!/usr/bin/env bash
# test_plot_fig3.sh FACEPUPPET: see CMakeLists.txt. Run from the source root.
set -u
fp=$1
script=bench/plot_fig3.py
py=${FACEPUPPET_PYTHON:-/usr/bin/python3}
[ -x "$py" ] || py=python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$py" "$script" --check 2>"$tmp/check.err"
case $? in
0) ;;
3) echo "SKIP: $(cat "$tmp/check.err")"; exit 77 ;;
*) fail "$py $script --check: $(cat "$tmp/check.err")" ;;
esac

# A PNG that is whole: signature, IHDR of a plausible size, every row inflated (stdlib only).
check_png() {
    "$py" - "$1" <<'PY' || fail "$1 is not a valid PNG of plausible size"
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert 10_000 < len(data) < 1_000_000, f"{len(data)} bytes"
assert data[:8] == b"\x89PNG\r\n\x1a\n", "signature"
pos, idat, w = 8, b"", None
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + n]
    assert zlib.crc32(kind + body) == struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])[0], kind
    if kind == b"IHDR":
        w, h, depth, color = struct.unpack(">IIBB", body[:10])
    elif kind == b"IDAT":
        idat += body
    pos += 12 + n
    if kind == b"IEND":
        break
assert w and 400 <= w <= 3000 and 300 <= h <= 2000, (w, h)
channels = {2: 3, 6: 4, 0: 1, 4: 2}[color]
assert depth == 8 and len(zlib.decompress(idat)) == h * (1 + w * channels), "pixel data"
print(f"{sys.argv[1]}: {w}x{h}, {len(data)} bytes")
PY
}

# 1. the command: a real quick table1, its rows on stdout (--json), the PNG renamed into place
"$fp" bench --quick --json --plot "$tmp/fig3.png" >"$tmp/t1.jsonl" 2>"$tmp/err" ||
    fail "bench --plot exited $?: $(tail -3 "$tmp/err")"
grep -q "wrote $tmp/fig3.png" "$tmp/err" || fail "no 'wrote' line: $(tail -2 "$tmp/err")"
[ "$(grep -c '"case":"table1"' "$tmp/t1.jsonl")" = 40 ] || fail "expected 40 table1 rows on stdout"
check_png "$tmp/fig3.png"
ls -a "$tmp" | grep -q '^\.fig3\.png\.' && fail "a temporary PNG was left behind"
# an existing PNG is refused before any work (73, named) unless --force, which replaces it
sum=$(md5sum <"$tmp/fig3.png")
"$fp" bench --quick --json --plot "$tmp/fig3.png" >"$tmp/t2.jsonl" 2>"$tmp/err"
rc=$?
[ $rc = 73 ] || fail "--plot onto an existing file: exit $rc, expected 73"
grep -q -- "--plot $tmp/fig3.png: exists (--force to overwrite)" "$tmp/err" ||
    fail "no message naming the existing PNG: $(cat "$tmp/err")"
[ -s "$tmp/t2.jsonl" ] && fail "the bench ran before the existing PNG was refused"
[ "$(md5sum <"$tmp/fig3.png")" = "$sum" ] || fail "the refused PNG was changed"
"$fp" bench --quick --plot "$tmp/fig3.png" --force >/dev/null 2>"$tmp/err" ||
    fail "bench --plot --force exited $?: $(tail -3 "$tmp/err")"
grep -q "wrote $tmp/fig3.png" "$tmp/err" || fail "--force: no 'wrote' line: $(tail -2 "$tmp/err")"
check_png "$tmp/fig3.png"

# 2. the script alone on the same rows (stdin and --in)
"$py" "$script" --in "$tmp/t1.jsonl" --out "$tmp/direct.png" || fail "script --in"
check_png "$tmp/direct.png"
"$py" "$script" --out "$tmp/stdin.png" <"$tmp/t1.jsonl" || fail "script on stdin"
check_png "$tmp/stdin.png"

# 3. errors: nothing written, the project's exit codes
echo '{"case":"scale","mode":"anchored"}' >"$tmp/none.jsonl"
"$py" "$script" --in "$tmp/none.jsonl" --out "$tmp/none.png" 2>"$tmp/err"
[ $? = 65 ] && grep -q "no table1 rows" "$tmp/err" && [ ! -e "$tmp/none.png" ] || fail "no rows: not 65"
echo '{"case":"table1","mode":"anchored","vertices":1089,"radius":10,"ms_median":0}' >"$tmp/bad.jsonl"
"$py" "$script" --in "$tmp/bad.jsonl" --out "$tmp/bad.png" 2>"$tmp/err"
[ $? = 65 ] && grep -q "line 1: ms_median" "$tmp/err" || fail "bad row: not 65 naming line and field"

FACEPUPPET_PYTHON=/nonexistent/python3 "$fp" bench --quick --plot "$tmp/a.png" 2>"$tmp/err"
[ $? = 69 ] && grep -q "needs python3" "$tmp/err" && [ ! -e "$tmp/a.png" ] ||
    fail "python3 missing: not 69: $(cat "$tmp/err")"

printf '#!/bin/sh\nexec "%s" -S -I "$@"\n' "$(command -v "$py")" >"$tmp/nompl"
chmod +x "$tmp/nompl"
if ! "$tmp/nompl" -c 'import matplotlib' 2>/dev/null; then # -S hides dist-packages
    FACEPUPPET_PYTHON=$tmp/nompl "$fp" bench --quick --plot "$tmp/b.png" 2>"$tmp/err"
    [ $? = 69 ] && grep -q "matplotlib" "$tmp/err" && [ ! -e "$tmp/b.png" ] ||
        fail "matplotlib missing: not 69: $(cat "$tmp/err")"
fi

"$fp" bench --quick --plot "$tmp/no/such/dir/c.png" 2>"$tmp/err"
[ $? = 73 ] || fail "unwritable folder: not 73: $(cat "$tmp/err")"
"$fp" bench --quick --case scale --plot "$tmp/d.png" 2>"$tmp/err"
[ $? = 64 ] && [ ! -e "$tmp/d.png" ] || fail "--case scale --plot: not 64"
# the frame case's mapping: a name no plugin has is an error of its own (78), named, before
# any frame is timed
"$fp" bench --case frame --mapping nosuch >"$tmp/out" 2>"$tmp/err"
[ $? = 78 ] || fail "--mapping nosuch: not 78: $(tail -2 "$tmp/err")"
grep -q "no mapping plugin named 'nosuch'" "$tmp/err" || fail "--mapping nosuch: the name not in: $(cat "$tmp/err")"
grep -q '^frame' "$tmp/out" && fail "--mapping nosuch: a frame was timed"
"$fp" bench --mapping >/dev/null 2>&1
[ $? = 64 ] || fail "--mapping without a name: not 64"
echo "test_plot_fig3: ok"
