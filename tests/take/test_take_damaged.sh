#!/bin/bash
# Hostile takes and stacks (an outside audit's files, made here from a take `run` records,
# each chunk's crc32 recomputed so only the field named is wrong):
#  1. export sizes from the frames' stored times: a take whose first frame says -1e18 ns is
#     refused before any work with --resample (73, its size said), not written for a minute;
#     frame times that do not increase are a damaged take (65, not usage's 64);
#  2. SIGTERM and SIGINT during an export: the temporary file removed, 143 and 130;
#  3. a control set the engine cannot take (radius NaN, 0, 1e300; a vector not finite) is a
#     damaged frame: the take is read as cut there, naming the file and the frame; no
#     "engine: invalid argument" line per frame over an exit 0;
#  4. a stack whose layer take has no intact frame: 65 naming the stack, layer and take;
#  5. bad data inside a .fpstack is 65 (an unknown landmark, a layer that is a stack); a
#     stack cut short says where it ends; takes rate refuses a take cut mid-chunk (no end
#     chunk) without --force, as its --help says; info of a take cut after its header says it
#     holds no frame.
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
pd=(--plugin-dir "$build/lib/facepuppet")
data=${FP_SHARED_DATA:-../shared/data}
mesh=$data/faces/mediapipe-canonical/canonical_face_model.obj
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-take-damaged-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
# expect STATUS cmd...: the exit status, stderr+stdout in $tmp/x.out
expect() { local want=$1; shift; "$@" >"$tmp/x.out" 2>&1; local got=$?
           [ $got -eq "$want" ] || { cat "$tmp/x.out"; fail "exit $got, want $want: $*"; }; }
has() { grep -q -- "$1" "$tmp/x.out" || { cat "$tmp/x.out"; fail "no \"$1\" in the output of: $2"; }; }
hasnt() { ! grep -q -- "$1" "$tmp/x.out" || { cat "$tmp/x.out"; fail "\"$1\" in the output of: $2"; }; }
temps() { ls -A "$1" | grep -c '^\.' ; }

"$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1" \
    --duration 2 --take-dir "$tmp/takes" --slate good -o "$tmp/run.obj" -q >"$tmp/run.out" 2>&1 ||
    { cat "$tmp/run.out"; fail "run exited $?"; }
good="$tmp/takes/good_T001.fptake"
d="$tmp/bad"
mkdir -p "$d"
# The hostile takes: every FRMS record patched by name (all_*), or one record (one_*).
python3 - "$good" "$d" <<'EOF' || fail "could not make the hostile takes"
import struct, sys, zlib
src = open(sys.argv[1], 'rb').read()
out = sys.argv[2]
def chunks(b):
    o, res = 16, []
    while o + 16 <= len(b):
        _, typ, ln, cnt = struct.unpack_from('<4s4sII', b, o)
        res.append([typ, bytearray(b[o + 16:o + 16 + ln]), cnt])
        o += 16 + ln + 4
    return res
def build(ch):
    b = bytearray(src[:16])
    for typ, p, cnt in ch:
        h = struct.pack('<4s4sII', b'FPCK', typ, len(p), cnt)
        b += h + p + struct.pack('<I', zlib.crc32(h + bytes(p)))
    return b
def records(ch):
    for c in ch:
        if c[0] == b'FRMS':
            o = 0
            while o < len(c[1]):
                yield c[1], o
                o += struct.unpack_from('<I', c[1], o)[0]
def write(name, ch):
    open('%s/%s_T001.fptake' % (out, name), 'wb').write(build(ch))
def patch_all(name, f):
    ch = chunks(src)
    for p, o in records(ch):
        f(p, o)
    write(name, ch)
def patch_nth(name, n, f):
    ch = chunks(src)
    for k, (p, o) in enumerate(records(ch)):
        if k == n:
            f(p, o)
    write(name, ch)
patch_all('allradnan', lambda p, o: struct.pack_into('<d', p, o + 32, float('nan')))
patch_all('allrad0', lambda p, o: struct.pack_into('<d', p, o + 32, 0.0))
patch_all('allradhuge', lambda p, o: struct.pack_into('<d', p, o + 32, 1e300))
patch_all('alltimezero', lambda p, o: struct.pack_into('<q', p, o + 16, 0))
patch_nth('timeback', 0, lambda p, o: struct.pack_into('<q', p, o + 16, -10**18))
# the first frame 10 s before the second: --resample 10000 writes 100000 frames (a slow export)
ch = chunks(src)
rs = list(records(ch))
t1 = struct.unpack_from('<q', rs[1][0], rs[1][1] + 16)[0]
struct.pack_into('<q', rs[0][0], rs[0][1] + 16, t1 - 10 * 10**9)
write('long', ch)
# a vector not finite in the last frame with control vectors: cut there
ch = chunks(src)
last = [(p, o) for p, o in records(ch) if struct.unpack_from('<I', p, o + 40)[0] > 0][-1]
struct.pack_into('<f', last[0], last[1] + 56 + 12, float('inf'))
write('vecinf', ch)
# a channel's value NaN in the last frame that has channels (the rig's jaw.open): cut there
ch = chunks(src)
withc = [(p, o) for p, o in records(ch) if struct.unpack_from('<I', p, o + 44)[0] > 0]
assert len(withc) > 3, "the good take has no channels"
p, o = withc[-1]
struct.pack_into('<f', p, o + 56 + 24 * struct.unpack_from('<I', p, o + 40)[0] + 32, float('nan'))
write('channan', ch)
# cut in its end chunk: no end chunk, some bytes of it
open('%s/cuttail_T001.fptake' % out, 'wb').write(src[:len(src) - 30])
EOF

# ---- 1. sizes from the stored times; times that do not increase -------------------------
start=$(date +%s)
expect 73 timeout 60 "$fp" export "$d/timeback_T001.fptake" --format pc2 --resample 30 -o "$tmp/tb.pc2" --force
has "about [0-9.]* GB (3000[0-9]* frames x 468 vertices), more than the .* free there; nothing written" "export timeback --resample 30"
[ ! -e "$tmp/tb.pc2" ] && [ "$(temps "$tmp")" -eq 0 ] || fail "export timeback left a file"
[ $(($(date +%s) - start)) -lt 20 ] || fail "export timeback was not refused before the work"
echo "1. timeback --resample 30: refused before any work: $(tail -1 "$tmp/x.out")"
expect 65 "$fp" export "$d/timeback_T001.fptake" --format glb -o "$tmp/tb.glb" -q
has "closer in time" "export timeback --format glb"
expect 65 "$fp" export "$d/alltimezero_T001.fptake" --format glb -o "$tmp/tz.glb" -q
has "alltimezero_T001.fptake: frame 1's time (0 ns) is not after frame 0's" "export alltimezero glb"
expect 65 "$fp" export "$d/alltimezero_T001.fptake" --format pc2 -o "$tmp/tz.pc2" -q
[ ! -e "$tmp/tz.pc2" ] && [ ! -e "$tmp/tz.glb" ] || fail "a damaged take's export left a file"
echo "1. frame times all equal: 65 ($(tail -1 "$tmp/x.out"))"
# the estimate is the frames' span: the long take's 10 s at 10000 fps, said over 1 GiB? No:
# 100001 x 468 x 12 bytes = 562 MB; with --resample 30000 it is 1.7 GB, said
expect 0 "$fp" export "$good" --format pc2 --resample 100 -o "$tmp/ok.pc2" -q
f=$(python3 -c "import struct,sys; print(struct.unpack_from('<i', open(sys.argv[1],'rb').read(), 28)[0])" "$tmp/ok.pc2")
[ "$f" -ge 195 ] && [ "$f" -le 202 ] || fail "a 2 s take at --resample 100 wrote $f frames"

# ---- 2. SIGTERM, SIGINT: the temporary file removed, 128 + the signal --------------------
for sig in TERM INT; do
    want=$([ $sig = TERM ] && echo 143 || echo 130)
    out="$tmp/sig$sig"
    mkdir -p "$out"
    "$fp" export "$d/long_T001.fptake" --format pc2 --resample 10000 -o "$out/x.pc2" -q \
        >"$tmp/sig.out" 2>&1 &
    pid=$!
    for ((i = 0; i < 200; i++)); do   # until the temporary file is there
        [ "$(temps "$out")" -gt 0 ] && break
        sleep 0.05
    done
    [ "$(temps "$out")" -gt 0 ] || { kill -KILL $pid; fail "SIG$sig: no temporary file seen"; }
    kill -$sig $pid
    wait $pid
    rc=$?
    cat "$tmp/sig.out"
    [ $rc -eq "$want" ] || fail "export stopped by SIG$sig exited $rc, want $want"
    [ "$(temps "$out")" -eq 0 ] || { ls -la "$out"; fail "SIG$sig left the temporary file"; }
    [ ! -e "$out/x.pc2" ] || fail "SIG$sig: the output was written"
    grep -q "SIG$sig: stopped" "$tmp/sig.out" || fail "SIG$sig: not said"
    echo "2. SIG$sig: exit $rc, no temporary file"
done
# SIGKILL: nothing runs, the temporary stays; the next export to that path removes it (its
# name holds the dead process's pid)
out="$tmp/sigKILL"
mkdir -p "$out"
"$fp" export "$d/long_T001.fptake" --format pc2 --resample 10000 -o "$out/x.pc2" -q >/dev/null 2>&1 &
pid=$!
for ((i = 0; i < 200; i++)); do [ "$(temps "$out")" -gt 0 ] && break; sleep 0.05; done
kill -KILL $pid; wait $pid
[ "$(temps "$out")" -eq 1 ] || fail "SIGKILL: $(temps "$out") temporary files, want the one it was writing"
ls -A "$out" | grep -q "^\.x\.pc2\.$pid\.......$" || fail "SIGKILL: the temporary's name holds no pid: $(ls -A "$out")"
expect 0 "$fp" export "$good" --format pc2 --resample 100 -o "$out/x.pc2" -q
[ "$(temps "$out")" -eq 0 ] || fail "the next export left the dead one's temporary: $(ls -A "$out")"
echo "2. SIGKILL: its temporary removed by the next export to the path"
# an existing output survives the signal (--force)
cp "$tmp/ok.pc2" "$tmp/keep.pc2"
"$fp" export "$d/long_T001.fptake" --format pc2 --resample 10000 -o "$tmp/keep.pc2" --force -q >/dev/null 2>&1 &
pid=$!
for ((i = 0; i < 200; i++)); do [ "$(temps "$tmp")" -gt 0 ] && break; sleep 0.05; done
kill -TERM $pid; wait $pid
cmp -s "$tmp/ok.pc2" "$tmp/keep.pc2" || fail "SIGTERM damaged the existing output"
[ "$(temps "$tmp")" -eq 0 ] || fail "SIGTERM (--force) left the temporary file"
"$fp" export --help | grep -q "128 + the" || fail "export --help does not say what a signal does"

# ---- 3. control sets the engine cannot take: damaged frames ------------------------------
for t in allradnan allrad0 allradhuge; do
    expect 65 "$fp" play "${pd[@]}" "$d/${t}_T001.fptake" -o "$tmp/p.obj" --force -q
    has "${t}_T001.fptake" "play $t"
    has "frame 0 (its record at byte [0-9]*): control set radius" "play $t"
    hasnt "engine: invalid argument" "play $t"
    expect 65 "$fp" export "$d/${t}_T001.fptake" --format pc2 -o "$tmp/p.pc2" -q
    [ ! -e "$tmp/p.pc2" ] || fail "export $t wrote a file"
done
echo "3. radius NaN, 0, 1e300: 65 ($(head -1 "$tmp/x.out"))"
expect 0 "$fp" play "${pd[@]}" "$d/vecinf_T001.fptake" -o "$tmp/v.obj" -q
has "vecinf_T001.fptake: cut at byte" "play vecinf"
has "control vector not finite" "play vecinf"
hasnt "engine: invalid argument" "play vecinf"
echo "3. a vector not finite: read as cut there ($(head -1 "$tmp/x.out"))"
# a channel's value NaN (was played without a word, the jaw left as it was): cut there, named
for cmd in play export; do
    if [ $cmd = play ]; then expect 0 "$fp" play "${pd[@]}" "$d/channan_T001.fptake" -o "$tmp/c.obj" --force
    else expect 0 "$fp" export "$d/channan_T001.fptake" --format pc2 -o "$tmp/c.pc2" --force; fi
    has "channan_T001.fptake: cut at byte [0-9]*: frame [0-9]* (its record at byte [0-9]*): channel \"jaw.open\" value not finite" "$cmd channan"
done
echo "3. a channel value not finite: read as cut there ($(grep -o 'frame [0-9]* .*' "$tmp/x.out" | head -1))"

# ---- 4. a stack whose layer take has no intact frame -------------------------------------
cp "$good" "$d/base_T001.fptake"
layer() { echo "{\"take\":\"$1\",\"region\":$2,\"mode\":\"replace\",\"in\":0,\"out\":null}"; }
stack() { echo "{\"format\":\"facepuppet-stack\",\"version\":1,\"layers\":[{\"take\":\"base_T001.fptake\"},$2]}" >"$d/$1.fpstack"; }
stack okv "$(layer base_T001.fptake '{"vertices":[[0,100]],"core_mm":1,"falloff_mm":5}')"
expect 0 "$fp" play "${pd[@]}" "$d/okv.fpstack" -o "$tmp/s.obj" --force -q
stack deadlayer "$(layer allradnan_T001.fptake '{"vertices":[[0,100]],"core_mm":1,"falloff_mm":5}')"
for cmd in play export; do
    if [ $cmd = play ]; then expect 65 "$fp" play "${pd[@]}" "$d/deadlayer.fpstack" -o "$tmp/s.obj" --force -q
    else expect 65 "$fp" export "$d/deadlayer.fpstack" --format pc2 -o "$tmp/s.pc2" -q; fi
    has "deadlayer.fpstack: layers\[1\]: .*allradnan_T001.fptake: no intact frame" "$cmd deadlayer"
done
echo "4. a layer with no intact frame: 65 ($(head -1 "$tmp/x.out"))"
# a layer cut short with intact frames plays them, said on stderr (as a take alone is)
stack cutlayer "$(layer vecinf_T001.fptake '{"vertices":[[0,100]],"core_mm":1,"falloff_mm":5}')"
expect 0 "$fp" play "${pd[@]}" "$d/cutlayer.fpstack" -o "$tmp/s.obj" --force -q
has "warning: .*cutlayer.fpstack: layers\[1\]: .*vecinf_T001.fptake: cut at byte .*; its [0-9]* intact frames played" "play cutlayer"

# ---- 5. bad data in a stack: 65; a stack cut short; takes rate of a take cut -------------
stack lm "$(layer base_T001.fptake '{"landmarks":["nosuch"],"core_mm":6,"falloff_mm":14}')"
expect 65 "$fp" play "${pd[@]}" "$d/lm.fpstack" -o "$tmp/s.obj" --force -q
has "lm.fpstack: layers\[1\]" "play lm"
stack vtx "$(layer base_T001.fptake '{"vertices":[[0,100000]],"core_mm":1,"falloff_mm":5}')"
expect 65 "$fp" play "${pd[@]}" "$d/vtx.fpstack" -o "$tmp/s.obj" --force -q
stack self "$(layer self.fpstack '{"vertices":[[0,10]],"core_mm":1,"falloff_mm":5}')"
expect 65 "$fp" play "${pd[@]}" "$d/self.fpstack" -o "$tmp/s.obj" --force -q
has "is a stack; a layer is a take" "play self"
head -c 100 "$d/okv.fpstack" >"$d/trunc.fpstack"
expect 65 "$fp" play "${pd[@]}" "$d/trunc.fpstack" -o "$tmp/s.obj" --force -q
has "trunc.fpstack: byte 100: not JSON: the text ends inside" "play trunc"
echo "5. stacks: 65; cut short: $(head -1 "$tmp/x.out")"
cp "$d/cuttail_T001.fptake" "$tmp/cut.fptake"
expect 73 "$fp" takes rate "$tmp/cut.fptake" 3
has "no end chunk" "takes rate cut"
cmp -s "$d/cuttail_T001.fptake" "$tmp/cut.fptake" || fail "takes rate rewrote a take with no end chunk"
expect 0 "$fp" takes rate --force "$tmp/cut.fptake" 3
echo "5. takes rate of a take with no end chunk: refused without --force"
# a take killed before its first chunk (its header alone): info says it holds no frame (before:
# "frames 0 (session frames 0..0)", a range of one frame), and play refuses it (65)
python3 - "$good" "$tmp/empty_T001.fptake" <<'PY' || fail "could not cut the take after its header"
import struct, sys
b = open(sys.argv[1], "rb").read()
open(sys.argv[2], "wb").write(b[:16 + 20 + struct.unpack_from("<I", b, 24)[0]])
PY
expect 0 "$fp" info "$tmp/empty_T001.fptake"
has "frames       0 (no intact frame)" "info of a header alone"
hasnt "session frames 0..0" "info of a header alone"
expect 65 "$fp" play "${pd[@]}" "$tmp/empty_T001.fptake" -o "$tmp/s.obj" --force -q
has "no intact frame to play" "play of a header alone"
echo "PASS"
