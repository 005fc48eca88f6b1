#!/usr/bin/env bash
# Export end to end (issue 14): on each face in ../shared/data, a take recorded by
# `facepuppet run --take-dir` from a real hand recording, then
#  1. export --format gltf and glb: the Khronos glTF-Validator reports 0 errors and 0
#     warnings; fp-export-check reads the file back with tinygltf and evaluates the animation
#     at every frame's time: every vertex within the stated error (0.1 mm, and 0.001 mm on
#     the ICT face, which takes more targets); `info` reads back its targets, keys and rate;
#  2. export --format pc2 and mdd: read back bit-exact against the played frames; `info`
#     gives their frames and points (and a cut PC2's, exit 65);
#  3. run --export and play --export give the same point caches byte for byte as export;
#  4. obj-seq: each file as play --frames-out writes it (byte-identical: both written back as
#     the input came in), the OBJ's non-vertex lines as in the input;
#  5. --range, --fps, and the refusals (exit codes).
set -uo pipefail
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
check="$build/tests/fp-export-check"
pd=(--plugin-dir "$build/lib/facepuppet")
data=${FP_SHARED_DATA:-../shared/data}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-export-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
expect() { local want=$1; shift; "$@" >"$tmp/x.out" 2>&1; local got=$?
           [ $got -eq "$want" ] || { cat "$tmp/x.out"; fail "exit $got, want $want: $*"; }; }

# The validator: node and the npm package gltf-validator (tools/gltf-validate; fp-setup
# installs it). Only a machine without node skips it.
validate=()
if command -v node >/dev/null; then
    if [ ! -d tools/gltf-validate/node_modules/gltf-validator ]; then
        command -v npm >/dev/null || fail "node without npm: cannot install gltf-validator"
        (cd tools/gltf-validate && npm ci --no-audit --no-fund >/dev/null 2>&1 ||
            npm install --no-audit --no-fund >/dev/null 2>&1) ||
            fail "npm could not install gltf-validator (tools/gltf-validate)"
    fi
    validate=(node tools/gltf-validate/validate.js)
else
    echo "SKIP (validator only): node is not installed, so the glTF-Validator does not run"
fi

faces=(ict-facekit/generic_neutral_mesh.obj:HandSplay-110fps
       lee-perry-smith/LeePerrySmith.obj:HandSplay-110fps
       mediapipe-canonical/canonical_face_model.obj:grab)
for entry in "${faces[@]}"; do
    face=${entry%%:*} rec=${entry##*:}
    name=$(basename "$(dirname "$face")")
    d="$tmp/$name"
    mkdir -p "$d"
    "$fp" run "${pd[@]}" --mesh "$data/faces/$face" --input "replay:$data/hands/leap-motion/${rec}_joints_mm.csv,fast=1" \
        --duration 4 --take-dir "$d/takes" --slate "$name" -o "$d/run.obj" --export "$d/run.pc2" -q \
        >"$d/run.out" 2>"$d/run.err" || { cat "$d/run.err"; fail "$name: run exited $?"; }
    take=$(ls "$d"/takes/*.fptake)
    for fmt in gltf glb; do
        "$fp" export "$take" --format $fmt --out "$d/take.$fmt" >"$d/export-$fmt.out" 2>&1 ||
            { cat "$d/export-$fmt.out"; fail "$name: export $fmt exited $?"; }
        echo "$name: $(head -1 "$d/export-$fmt.out")"
        if [ ${#validate[@]} -gt 0 ]; then
            "${validate[@]}" "$d/take.$fmt" >"$d/validate-$fmt.out" 2>&1 ||
                { cat "$d/validate-$fmt.out"; fail "$name: the glTF-Validator found errors or warnings in $fmt"; }
            echo "$name: $(head -1 "$d/validate-$fmt.out")"
        fi
        "$check" "$take" "$d/take.$fmt" --max-error 0.1 || fail "$name: $fmt read back"
        # info reads the document back through tinygltf: the export's targets, keys and rate
        k=$(sed -n 's/.*K = \([0-9]*\) morph targets.*/\1/p' "$d/export-$fmt.out")
        f=$(sed -n 's/.*exported \([0-9]*\) frames.*/\1/p' "$d/export-$fmt.out")
        "$fp" info "$d/take.$fmt" >"$d/info-$fmt.out" 2>&1 &&
            grep -q "^  targets   $k morph targets\?$" "$d/info-$fmt.out" &&
            grep -q "^  animation .*1 channel (1 of morph weights), $f keys, .* 60 fps" "$d/info-$fmt.out" &&
            grep -q "^  scale     root node " "$d/info-$fmt.out" ||
            { cat "$d/info-$fmt.out"; fail "$name: info take.$fmt ($k targets, $f keys at 60 fps)"; }
    done
    for fmt in pc2 mdd; do
        "$fp" export "$take" --format $fmt --out "$d/take.$fmt" -q || fail "$name: export $fmt exited $?"
        "$check" "$take" "$d/take.$fmt" || fail "$name: $fmt read back"
    done
    cmp -s "$d/run.pc2" "$d/take.pc2" || fail "$name: run --export differs from export --format pc2"
    "$fp" play "${pd[@]}" "$take" --export "$d/play.mdd" -q || fail "$name: play --export exited $?"
    cmp -s "$d/play.mdd" "$d/take.mdd" || fail "$name: play --export differs from export --format mdd"
    echo "$name: run --export, play --export and export give the same point caches"
    # info reads them back (before: "unknown format" of a recording): the take's frames and
    # the mesh's points, the MDD's rate; a cache cut short exits 65 and says how much it holds
    n=$("$fp" info "$take" | sed -n 's/^  frames *\([0-9]*\).*/\1/p')
    v=$("$fp" info "$data/faces/$face" | sed -n 's/^  vertices *\([0-9]*\).*/\1/p')
    "$fp" info "$d/take.pc2" >"$d/info-pc2.out" 2>&1 && grep -q "^  points    $v$" "$d/info-pc2.out" &&
        grep -q "^  frames    $n$" "$d/info-pc2.out" || { cat "$d/info-pc2.out"; fail "$name: info take.pc2 ($n frames, $v points)"; }
    "$fp" info "$d/take.mdd" >"$d/info-mdd.out" 2>&1 && grep -q "^  frames    $n$" "$d/info-mdd.out" &&
        grep -q "fps" "$d/info-mdd.out" || { cat "$d/info-mdd.out"; fail "$name: info take.mdd"; }
    head -c $((32 + 12 * v * 2 + 5)) "$d/take.pc2" >"$d/cut.pc2"
    expect 65 "$fp" info "$d/cut.pc2"
    grep -q "cut: the file holds 2 of them" "$tmp/x.out" || { cat "$tmp/x.out"; fail "$name: info of a cut PC2"; }
done

# a tighter error on the ICT face: more targets, still within it at every frame
ict="$tmp/ict-facekit"
take=$(ls "$ict"/takes/*.fptake)
"$fp" export "$take" --format glb --out "$ict/tight.glb" --max-error 0.001 >"$ict/tight.out" ||
    fail "export --max-error 0.001 exited $?"
echo "ict-facekit: $(head -1 "$ict/tight.out")"
"$check" "$take" "$ict/tight.glb" --max-error 0.001 || fail "ict: 0.001 mm read back"
if [ ${#validate[@]} -gt 0 ]; then
    "${validate[@]}" "$ict/tight.glb" >"$ict/tight-v.out" || { cat "$ict/tight-v.out"; fail "validator: tight.glb"; }
fi

# obj-seq: frames 20-24 as play --frames-out writes them
"$fp" export "$take" --format obj-seq --range 20-24 --out "$ict/seq" -q || fail "obj-seq exited $?"
[ "$(ls "$ict/seq" | wc -l)" -eq 5 ] || fail "obj-seq: $(ls "$ict/seq" | wc -l) files, want 5"
"$fp" play "${pd[@]}" "$take" --frames-out "$ict/play" -q || fail "play --frames-out exited $?"
play_files=($(ls "$ict/play")) seq_files=($(ls "$ict/seq"))
for i in 0 1 2 3 4; do
    cmp -s "$ict/seq/${seq_files[i]}" "$ict/play/${play_files[20 + i]}" ||
        fail "obj-seq frame $i differs from play's frame $((20 + i))"
done
diff <(grep -v '^v ' "$data/faces/ict-facekit/generic_neutral_mesh.obj") <(grep -v '^v ' "$ict/seq/${seq_files[0]}") >/dev/null ||
    fail "obj-seq: the OBJ's faces, UVs, groups or materials changed"
echo "ict-facekit: obj-seq frames 20-24 byte-identical to play's; faces, vt, usemtl, mtllib as in the input"

# --range by timecode and --fps resampling (PC2 has one frame per sample)
frames=$("$check" "$take" "$ict/take.pc2" | sed -n 's/.*: \([0-9]*\) frames.*/\1/p')
"$fp" export "$take" --format pc2 --fps 30 --out "$ict/30.pc2" -q || fail "--fps 30 exited $?"
n30=$(od -An -tu4 -j28 -N4 "$ict/30.pc2" | tr -d ' ')
[ "$n30" -ge $((frames / 2 - 1)) ] && [ "$n30" -le $((frames / 2 + 1)) ] ||
    fail "--fps 30: $n30 samples from $frames frames at 60 fps"
"$fp" export "$take" --format pc2 --range 10-19 --out "$ict/r.pc2" -q || fail "--range exited $?"
[ "$(od -An -tu4 -j28 -N4 "$ict/r.pc2" | tr -d ' ')" -eq 10 ] || fail "--range 10-19: not 10 frames"
cmp -s <(tail -c $((10 * 26719 * 12)) "$ict/r.pc2") \
       <(dd if="$ict/take.pc2" bs=1 skip=$((32 + 10 * 26719 * 12)) count=$((10 * 26719 * 12)) 2>/dev/null) ||
    fail "--range 10-19: frames differ from the whole export's"
echo "ict-facekit: --fps 30 gives $n30 samples of $frames frames; --range 10-19 the same 10 frames"
# --resample F of the 60 fps take: sample k (at k/F s) is the take's frame floor(60k/F) bit for
# bit, and the last sample is the last frame where it falls on the grid. A frame on the grid
# whose time, stored in whole ns, reads up to 0.5 ns late (10/60 s: 166666667 ns) showed the
# frame before it (sample 40 of --resample 24 was frame 99, not 100: 3.35 mm off in Blender).
fb=$((26719 * 12))
for F in 24 30; do
    "$fp" export "$take" --format pc2 --resample $F --out "$ict/rs$F.pc2" -q || fail "--resample $F exited $?"
    n=$(od -An -tu4 -j28 -N4 "$ict/rs$F.pc2" | tr -d ' ')
    [ "$n" -eq $(((frames - 1) * F / 60 + 1)) ] || fail "--resample $F: $n samples of $frames frames at 60 fps"
    for ((k = 0; k < n; k++)); do
        j=$((60 * k / F))
        cmp -s <(tail -c +$((33 + k * fb)) "$ict/rs$F.pc2" | head -c $fb) \
               <(tail -c +$((33 + j * fb)) "$ict/take.pc2" | head -c $fb) ||
            fail "--resample $F: sample $k ($k/$F s) is not the take's frame $j"
    done
done
echo "ict-facekit: --resample 24 and 30: every sample the take's frame at its time, bit for bit"

# png-seq: rendered headless as the viewer draws the face (under Xvfb), the asked size
if "$fp" live --help >/dev/null 2>&1 && command -v xvfb-run >/dev/null; then
    LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1280x720x24" "$fp" export "$take" --format png-seq \
        --range 30-32 --size 320x240 --camera 20,5,1.2 --out "$ict/png" -q || fail "png-seq exited $?"
    pngs=($(ls "$ict/png"))
    [ ${#pngs[@]} -eq 3 ] || fail "png-seq: ${#pngs[@]} files, want 3"
    for p in "${pngs[@]}"; do
        python3 - "$ict/png/$p" <<'PY' || fail "png-seq: $p"
import struct, sys, zlib
b = open(sys.argv[1], 'rb').read()
assert b[:8] == b'\x89PNG\r\n\x1a\n', 'not a PNG'
w, h = struct.unpack('>II', b[16:24])
assert (w, h) == (320, 240), (w, h)
# the pixels: not one colour (the face is drawn on the background)
data, i = b'', 8
while i < len(b):
    n, = struct.unpack('>I', b[i:i + 4]); t = b[i + 4:i + 8]
    if t == b'IDAT': data += b[i + 8:i + 8 + n]
    i += 12 + n
raw = zlib.decompress(data)
assert len(set(raw[1:1 + w * 3])) >= 1 and len(set(raw)) > 20, 'blank picture'
PY
    done
    echo "ict-facekit: png-seq frames 30-32 at 320x240 rendered under Xvfb"
    DISPLAY= expect 66 "$fp" export "$take" --format png-seq --range 0-0 --out "$ict/png-none"
else
    echo "SKIP (png-seq only): no viewer in this build or no xvfb-run"
fi

# refusals
expect 64 "$fp" export "$take" --format fbx
expect 64 "$fp" export "$take"
expect 64 "$fp" export "$take" --format png-seq --size 10x10
expect 64 "$fp" export "$take" --format pc2 --range 5
# a frame index is digits (a '+' as in every number): strtoull skipped a blank
expect 64 "$fp" export "$take" --format pc2 --range " 5-10"
grep -q "range ' 5-10': ' 5' is neither a frame index nor a timecode" "$tmp/x.out" || { cat "$tmp/x.out"; fail "--range ' 5-10'"; }
expect 64 "$fp" export "$take" --format pc2 --range "5- 10"
expect 0 "$fp" export "$take" --format pc2 --range +5-+6 --out "$tmp/plus.pc2" -q
expect 66 "$fp" export "$tmp/none.fptake" --format pc2
# a drop-frame take (29.97 fps): --range's timecodes are written as its own, HH:MM:SS;FF; one
# written HH:MM:SS:FF counted non-drop, thousands of frames off in the day ("IN is past the
# take's last frame" for the take's own first timecode), and is refused saying so
mp="$data/faces/mediapipe-canonical/canonical_face_model.obj"
"$fp" run "${pd[@]}" --mesh "$mp" --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1" \
    --fps 29.97 --duration 1 --take-dir "$tmp/df" --slate df -o "$tmp/df.obj" -q >/dev/null 2>&1 ||
    fail "run --fps 29.97 exited $?"
dftake=$(ls "$tmp"/df/*.fptake)
tcin=$("$fp" info "$dftake" | sed -n 's/^  timecode *\([0-9:;]*\) - .*/\1/p')
[[ $tcin == *";"* ]] || fail "the 29.97 fps take's timecode in '$tcin' is not drop-frame"
dfn=$("$fp" info "$dftake" | sed -n 's/^  frames *\([0-9]*\) .*/\1/p')
expect 0 "$fp" export "$dftake" --format pc2 --range "$tcin-" --out "$tmp/df.pc2" -q
[ "$(od -An -tu4 -j28 -N4 "$tmp/df.pc2" | tr -d ' ')" -eq "$dfn" ] || fail "--range $tcin-: not the take's $dfn frames"
expect 64 "$fp" export "$dftake" --format pc2 --range "${tcin/;/:}-" --out "$tmp/df2.pc2"
grep -q "the take's timecodes are drop-frame ($tcin - .*): write them HH:MM:SS;FF" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "--range ${tcin/;/:}- on a drop-frame take: not said"; }
# a face written Z-up (Blender's axes: x, -z, y) and run with --up +z --facing -y: the glb's
# root node turns its up to glTF's +y and its front to +z (without the turn Blender showed it on
# its back), on export and run --export alike; fp-export-check reads the turn back
awk '/^v /{printf "v %s %s %s\n",$2,-$4,$3; next} /^vn /{printf "vn %s %s %s\n",$2,-$4,$3; next} {print}' \
    "$mp" >"$tmp/zup.obj"
"$fp" run "${pd[@]}" --mesh "$tmp/zup.obj" --up +z --facing -y --duration 1 \
    --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1" --take-dir "$tmp/zup" \
    --slate zup -o "$tmp/zup-out.obj" --export "$tmp/zup-run.glb" -q >/dev/null 2>&1 ||
    fail "run on the Z-up face exited $?"
ztake=$(ls "$tmp"/zup/*.fptake)
"$fp" export "$ztake" --format glb --out "$tmp/zup.glb" -q || fail "export of the Z-up take exited $?"
for g in zup.glb zup-run.glb; do
    "$check" "$ztake" "$tmp/$g" >"$tmp/zup-check.out" 2>&1 &&
        grep -q "up turned to (0 1 0), its front to (0 0 1)" "$tmp/zup-check.out" ||
        { cat "$tmp/zup-check.out"; fail "$g: the Z-up face is not turned to +y up, +z front"; }
done
echo "mediapipe Z-up: the glb's root turns the face to +y up and +z front (export and run --export)"
# -q on play and export prints errors and warnings alone: the session's line on the turned
# face ("the face looks along ... the hands are placed in front of it") printed under it
expect 0 "$fp" export "${pd[@]}" "$ztake" --format pc2 --out "$tmp/zup.pc2" -q
[ ! -s "$tmp/x.out" ] || { cat "$tmp/x.out"; fail "export -q of the Z-up take printed the lines above"; }
expect 0 "$fp" play "${pd[@]}" "$ztake" -o "$tmp/zup-play.obj" -q
[ ! -s "$tmp/x.out" ] || { cat "$tmp/x.out"; fail "play -q of the Z-up take printed the lines above"; }
expect 64 "$fp" export "$take" --format pc2 --out ""
grep -qx "facepuppet export: --out: give a file or folder name (it is empty)" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "--out '': not said as an empty name"; }
# A write that fails (over the file size limit, write() gets EFBIG) names the file once, after
# the command's one prefix, in every format: glb and gltf said "facepuppet export: export:
# FILE: write failed: ...". play --export names its option, as on opening.
small=$(ls "$tmp"/mediapipe-canonical/takes/*.fptake)
for fmt in glb gltf pc2 mdd; do
    ( ulimit -f 1; trap '' XFSZ; exec "$fp" export "$small" --format $fmt --out "$tmp/big.$fmt" -q ) \
        >"$tmp/x.out" 2>&1
    rc=$?
    [ $rc -eq 73 ] || { cat "$tmp/x.out"; fail "$fmt over the file size limit: exit $rc, want 73"; }
    grep -qx "facepuppet export: $tmp/big.$fmt: write failed: File too large.*" "$tmp/x.out" ||
        { cat "$tmp/x.out"; fail "$fmt: not 'facepuppet export: FILE: write failed: ...'"; }
    [ ! -e "$tmp/big.$fmt" ] || fail "$fmt: a file was left over the file size limit"
done
( ulimit -f 1; trap '' XFSZ; exec "$fp" play "${pd[@]}" "$small" --export "$tmp/big.glb" -q ) >"$tmp/x.out" 2>&1
rc=$?
[ $rc -eq 73 ] || { cat "$tmp/x.out"; fail "play --export over the file size limit: exit $rc, want 73"; }
grep -qx "facepuppet play: --export: $tmp/big.glb: write failed: File too large.*" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "play --export: not 'facepuppet play: --export: FILE: write failed: ...'"; }
echo "a failed write: one prefix and the file, in glb, gltf, pc2, mdd and play --export"
expect 73 "$fp" export "$take" --format pc2 --out /proc/nope/x.pc2
# An output that is an input is refused, --force or not (73), the input left as it was:
# `export T.fptake --format pc2 --out T.fptake --force` replaced the take by its point cache
# (a link to it too); a stack's layer take, the mesh (export and play) likewise.
cp "$small" "$tmp/self.fptake"
cp "$data/faces/mediapipe-canonical/canonical_face_model.obj" "$tmp/self.obj"
ln -s self.fptake "$tmp/self-link.pc2"
sum=$(cksum <"$tmp/self.fptake") msum=$(cksum <"$tmp/self.obj")
for c in "export --format pc2 --out self.fptake" "export --format mdd --out self-link.pc2" \
         "export --format pc2 --mesh self.obj --out self.obj" "play --mesh self.obj --out self.obj" \
         "play --export self-link.pc2"; do
    set -- $c
    cmd=$1; shift
    args=(); for w in "$@"; do case $w in self*) args+=("$tmp/$w") ;; *) args+=("$w") ;; esac; done
    expect 73 "$fp" $cmd "${pd[@]}" "$tmp/self.fptake" "${args[@]}" --force -q
    grep -q "^facepuppet $cmd: .*: is the \(take\|mesh\) being read (.*): refused (it would be written over)" \
        "$tmp/x.out" || { cat "$tmp/x.out"; fail "$c: not 'is the take/mesh being read ... refused'"; }
    [ "$(cksum <"$tmp/self.fptake")" = "$sum" ] && [ "$(cksum <"$tmp/self.obj")" = "$msum" ] ||
        fail "$c --force: the input was written over"
done
printf '{"format":"facepuppet-stack","version":1,"layers":[{"take":"self.fptake"},{"take":"self2.fptake","mode":"add"}]}' \
    >"$tmp/self.fpstack"
cp "$small" "$tmp/self2.fptake"
sum2=$(cksum <"$tmp/self2.fptake")
expect 73 "$fp" export "${pd[@]}" "$tmp/self.fpstack" --format pc2 --out "$tmp/self2.fptake" --force -q
grep -q "is a take of the stack being read" "$tmp/x.out" || { cat "$tmp/x.out"; fail "a stack's take as --out"; }
[ "$(cksum <"$tmp/self2.fptake")" = "$sum2" ] || fail "export of a stack wrote over its layer's take"
expect 0 "$fp" export "${pd[@]}" "$tmp/self.fpstack" --format pc2 --out "$tmp/stack.pc2" -q
# the soundtrack: --out beside it with its name (line.glb -> line.wav) would write the WAV over it
python3 -c "import wave; w = wave.open('$tmp/line.wav', 'wb'); w.setnchannels(1); w.setsampwidth(2);
w.setframerate(8000); w.writeframes(bytes(2 * 8000 * 2)); w.close()"
expect 0 "$fp" run "${pd[@]}" --mesh "$tmp/self.obj" --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1" \
    --duration 0.5 --take-dir "$tmp/aud" --slate aud --audio "$tmp/line.wav" --audio-out null -q -o "$tmp/aud.obj"
wsum=$(cksum <"$tmp/line.wav")
expect 73 "$fp" export "${pd[@]}" "$tmp/aud/aud_T001.fptake" --format glb --out "$tmp/line.glb" --force -q
grep -q "line.wav: is the take's soundtrack being read" "$tmp/x.out" || { cat "$tmp/x.out"; fail "the soundtrack as the WAV"; }
[ "$(cksum <"$tmp/line.wav")" = "$wsum" ] && [ ! -e "$tmp/line.glb" ] || fail "the soundtrack was written over"
echo "an output that is an input (take, link to it, a stack's take, the mesh, the soundtrack): refused, 73"
# --max-targets K: at most K targets in the file, the offset that keeps the weights in [0, 1]
# counted (it made K + 1); the weights in [0, 1] all the same (fp-export-check)
for k in 2 3 5; do
    expect 0 "$fp" export "${pd[@]}" "$small" --format glb --max-targets $k --out "$tmp/cap$k.glb" --force
    got=$("$fp" info "$tmp/cap$k.glb" | sed -n 's/^ *targets *\([0-9]*\) morph targets.*/\1/p')
    [ -n "$got" ] && [ "$got" -le $k ] || { cat "$tmp/x.out"; fail "--max-targets $k: $got targets in the file"; }
    grep -q "K = $got morph targets" "$tmp/x.out" || { cat "$tmp/x.out"; fail "--max-targets $k: the line's K is not the file's $got"; }
    "$check" "$small" "$tmp/cap$k.glb" --max-error 1000 >"$tmp/x.out" 2>&1 ||
        { cat "$tmp/x.out"; fail "--max-targets $k: fp-export-check"; }
done
echo "--max-targets: at most K targets in the file, the offset counted"
# An obj-seq written with --force over a longer one of the same take: the folder holds the new
# frames alone (3 exported over 6 left frames 3-5 of the old export after them, which a
# sequence importer played on); files of other names (a png-seq's beside it too) are left
stem=$(basename "$small" .fptake)
expect 0 "$fp" export "${pd[@]}" "$small" --format obj-seq --range 0-5 --out "$tmp/reseq" -q
touch "$tmp/reseq/notes.txt" "$tmp/reseq/other_000009.obj" "$tmp/reseq/${stem}_000007.png"
expect 0 "$fp" export "${pd[@]}" "$small" --format obj-seq --range 10-12 --out "$tmp/reseq" --force
grep -q "removed 3 frames of an earlier export from $tmp/reseq (${stem}_000003.obj ...)" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "obj-seq --force over a longer sequence: the removal not said"; }
[ "$(ls "$tmp/reseq" | tr '\n' ' ')" = "${stem}_000000.obj ${stem}_000001.obj ${stem}_000002.obj ${stem}_000007.png notes.txt other_000009.obj " ] ||
    fail "obj-seq --force over a longer sequence left: $(ls "$tmp/reseq" | tr '\n' ' ')"
"$fp" play "${pd[@]}" "$small" --frames-out "$tmp/replay" -q >/dev/null 2>&1 || fail "play --frames-out exited $?"
for i in 0 1 2; do
    cmp -s "$tmp/reseq/${stem}_00000$i.obj" "$tmp/replay/$(ls "$tmp/replay" | sed -n "$((11 + i))p")" ||
        fail "obj-seq --force: frame $i is not the take's frame $((10 + i))"
done
echo "obj-seq --force over a longer sequence: the folder holds the 3 new frames alone"
# --frames-out DIR --force (run, play: the frames an export is checked against) over an earlier
# run's: the folder holds the new frames alone (a run at 24 fps over one at 60 left
# frame_000001_t0.017s.obj beside frame_000001_t0.042s.obj, 85 files for 25 frames)
expect 0 "$fp" run "${pd[@]}" --mesh "$mp" --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1" \
    --duration 1 -o "$tmp/fo.obj" --frames-out "$tmp/fo" -q
touch "$tmp/fo/notes.txt"
expect 0 "$fp" run "${pd[@]}" --mesh "$mp" --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1" \
    --duration 1 --fps 24 -o "$tmp/fo.obj" --frames-out "$tmp/fo" --force
grep -q "^facepuppet run: --frames-out $tmp/fo: removed 61 frames of an earlier run" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "run --frames-out --force: the removal of the earlier run's frames not said"; }
[ "$(ls "$tmp/fo" | grep -c '^frame_')" -eq 25 ] && [ -e "$tmp/fo/notes.txt" ] &&
    [ "$(ls "$tmp/fo" | grep '^frame_' | sed -n 2p)" = frame_000001_t0.042s.obj ] ||
    fail "run --frames-out --force at 24 fps over 60 left: $(ls "$tmp/fo" | head -4 | tr '\n' ' ')... ($(ls "$tmp/fo" | wc -l) files)"
dfn=$("$fp" info "$dftake" | sed -n 's/^  frames *\([0-9]*\) .*/\1/p')
expect 0 "$fp" play "${pd[@]}" "$small" --frames-out "$tmp/fo" --force -q
expect 0 "$fp" play "${pd[@]}" "$dftake" --frames-out "$tmp/fo" --force -q
[ "$(ls "$tmp/fo" | grep -c '^frame_')" -eq "$dfn" ] ||
    fail "play --frames-out --force of a $dfn-frame take over a longer one left $(ls "$tmp/fo" | grep -c '^frame_') frames"
echo "--frames-out --force (run, play): the folder holds the new run's frames alone"
# A take with no end chunk (still recording, or its recorder killed): exported whole as far as
# it goes, with a warning (it said nothing: a take exported mid-recording was silently short)
off=$(grep -obUa "FPCKTAIL" "$small" | tail -1 | cut -d: -f1)
[ -n "$off" ] || fail "no TAIL chunk in $small"
head -c "$off" "$small" >"$tmp/open.fptake"
expect 0 "$fp" export "${pd[@]}" "$tmp/open.fptake" --format pc2 --out "$tmp/open.pc2"
grep -q "^facepuppet export: warning: $tmp/open.fptake: no end chunk: it may still be recording" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "a take with no end chunk exported without a warning"; }
expect 0 "$fp" export "${pd[@]}" "$small" --format pc2 --out "$tmp/closed.pc2"
! grep -q "no end chunk" "$tmp/x.out" || { cat "$tmp/x.out"; fail "a closed take warned of no end chunk"; }
cmp -s "$tmp/open.pc2" "$tmp/closed.pc2" || fail "the take without its end chunk exported other frames"
echo "a take with no end chunk: exported with a warning, the same frames"
# A take recorded across midnight (its timecode in set to 23:59:58:00, the HEAD's crc32 made
# again): --range by timecodes after midnight is the take's frames a day on (00:00:00:00 is
# frame 120 at 60 fps), not "OUT is before the take's first frame"
python3 - "$small" "$tmp/midnight.fptake" <<'PY' || fail "could not write the midnight take"
import re, struct, sys, zlib
b = bytearray(open(sys.argv[1], 'rb').read())
i = b.find(b'FPCKHEAD')
n = struct.unpack_from('<I', b, i + 8)[0]
head = re.sub(rb'"timecode_in":"\d\d:\d\d:\d\d:\d\d"', b'"timecode_in":"23:59:58:00"', bytes(b[i + 16:i + 16 + n]))
assert len(head) == n
b[i + 16:i + 16 + n] = head
struct.pack_into('<I', b, i + 16 + n, zlib.crc32(bytes(b[i:i + 16]) + head) & 0xffffffff)
open(sys.argv[2], 'wb').write(b)
PY
"$fp" info "$tmp/midnight.fptake" | grep -q "^  timecode *23:59:58:00 - 00:00:0" || fail "the midnight take's timecodes"
expect 0 "$fp" export "${pd[@]}" "$tmp/midnight.fptake" --format pc2 --range 00:00:00:00-00:00:01:00 --out "$tmp/mid.pc2" -q
expect 0 "$fp" export "${pd[@]}" "$tmp/midnight.fptake" --format pc2 --range 120-180 --out "$tmp/mid-idx.pc2" -q
cmp -s "$tmp/mid.pc2" "$tmp/mid-idx.pc2" || fail "--range 00:00:00:00-00:00:01:00 past midnight is not frames 120-180"
expect 0 "$fp" export "${pd[@]}" "$tmp/midnight.fptake" --format pc2 --range 23:59:59:00-00:00:00:30 --out "$tmp/mid2.pc2" -q
[ "$(od -An -tu4 -j28 -N4 "$tmp/mid2.pc2" | tr -d ' ')" -eq 91 ] || fail "--range 23:59:59:00-00:00:00:30 across midnight: not 91 frames"
expect 64 "$fp" export "${pd[@]}" "$tmp/midnight.fptake" --format pc2 --range 00:00:05:00- --out "$tmp/mid3.pc2"
grep -q "IN is past the take's last frame" "$tmp/x.out" || { cat "$tmp/x.out"; fail "--range 00:00:05:00- past the midnight take"; }
echo "a take across midnight: --range by timecodes after midnight, and across it"
# A point cache named as another format (an MDD in x.pc2, read as a PC2 by what goes by the
# name) is refused before any work
expect 64 "$fp" export "${pd[@]}" "$small" --format mdd --out "$tmp/named.pc2"
grep -q "the name says pc2, not mdd" "$tmp/x.out" || { cat "$tmp/x.out"; fail "--format mdd --out x.pc2"; }
expect 64 "$fp" export "${pd[@]}" "$small" --format pc2 --out "$tmp/named.glb"
[ ! -e "$tmp/named.pc2" ] && [ ! -e "$tmp/named.glb" ] || fail "a point cache named as another format was written"
expect 0 "$fp" export "${pd[@]}" "$small" --format mdd --out "$tmp/named.cache" -q
# An export larger than the room free where it goes: refused before any frame (73), naming the
# size (a --fps of 10000 for 100 wrote 10.6 GB of a 3.3 s take, unasked). A 1 MiB tmpfs in a
# user namespace (unshare -r -m); skipped where the system allows none.
mkdir -p "$tmp/room"
if unshare -r -m sh -c 'mount -t tmpfs -o size=1m tmpfs "$1"' _ "$tmp/room" 2>/dev/null; then
    for fmt in pc2 mdd obj-seq; do
        unshare -r -m bash -c 'mount -t tmpfs -o size=1m tmpfs "$1/room" &&
                               exec "$2" export "$3" --format "$4" --out "$1/room/out.$4"' _ "$tmp" "$fp" "$take" $fmt \
            >"$tmp/x.out" 2>&1
        rc=$?
        [ $rc -eq 73 ] || { cat "$tmp/x.out"; fail "$fmt larger than the room free: exit $rc, want 73"; }
        grep -q "out.$fmt: about [0-9]* MB (.* frames x 26719 vertices), more than the 1 MB free there; nothing written" \
            "$tmp/x.out" || { cat "$tmp/x.out"; fail "$fmt larger than the room free: no size said"; }
    done
    echo "an export larger than the room free: refused before any frame, in pc2, mdd and obj-seq"
    # run and play check theirs too where the frames are known before the first (play: the
    # take's; run: --duration's): --frames-out and --export refused, and nothing left in the
    # room (a --frames-out folder the refused command made is taken away)
    room() { unshare -r -m bash -c 'mount -t tmpfs -o size=1m tmpfs "$1/room" && d=$1 && shift &&
                                    cd "$d/room" && "$@"; rc=$?; ls -A | sed "s/^/left: /"; exit $rc' \
                 _ "$tmp" "$@" >"$tmp/x.out" 2>&1; }
    ict_mesh="$data/faces/ict-facekit/generic_neutral_mesh.obj"
    grab="replay:$data/hands/leap-motion/grab_joints_mm.csv,fast=1"
    for c in "play --frames-out fr" "play --export x.pc2" "run --frames-out fr" "run --export x.mdd"; do
        set -- $c
        if [ "$1" = play ]; then room "$fp" play "${pd[@]}" "$take" "$2" "$3"
        else room "$fp" run "${pd[@]}" --mesh "$ict_mesh" --input "$grab" --duration 2 -q "$2" "$3"; fi
        rc=$?
        [ $rc -eq 73 ] || { cat "$tmp/x.out"; fail "$c larger than the room free: exit $rc, want 73"; }
        grep -q "^facepuppet $1: $2 $3: about [0-9]* MB ([0-9]* frames x 26719 vertices), more than the 1 MB free there; nothing written" \
            "$tmp/x.out" || { cat "$tmp/x.out"; fail "$c larger than the room free: no size said"; }
        ! grep -q "^left: " "$tmp/x.out" || { cat "$tmp/x.out"; fail "$c refused, but left a file or folder"; }
    done
    # an --out the room cannot hold (the ICT face's 2.8 MB) fails the run (73), and the export
    # beside it, which fits elsewhere, is still finished: each output stands alone
    rm -f "$tmp/kept.pc2"
    room "$fp" run "${pd[@]}" --mesh "$ict_mesh" --input "$grab" --duration 0.5 -q --out o.obj --export "$tmp/kept.pc2"
    rc=$?
    [ $rc -eq 73 ] || { cat "$tmp/x.out"; fail "--out larger than the room free: exit $rc, want 73"; }
    grep -q "o.obj: write failed: No space left on device" "$tmp/x.out" || { cat "$tmp/x.out"; fail "--out: no write failure said"; }
    [ -s "$tmp/kept.pc2" ] || { cat "$tmp/x.out"; fail "--out failed and the --export beside it was lost"; }
    n=$(od -An -tu4 -j28 -N4 "$tmp/kept.pc2" | tr -d ' ')
    [ "$(stat -c %s "$tmp/kept.pc2")" -eq $((32 + n * 12 * 26719)) ] && [ "$n" -gt 0 ] ||
        fail "the --export kept beside a failed --out is not a whole point cache ($n frames)"
    echo "run and play: --frames-out and --export larger than the room refused before any frame," \
         "nothing left; a failed --out keeps the export beside it ($n frames)"
else
    echo "SKIP (room check only): no user namespace to mount a small file system in here"
fi
expect 64 "$fp" run "${pd[@]}" --mesh "$data/faces/ict-facekit/generic_neutral_mesh.obj" --input "replay:x.csv" --export x.fbx
[ ! -e /proc/nope/x.pc2 ] || true
echo "PASS"
