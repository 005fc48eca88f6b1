#!/usr/bin/env bash
# No silent surprises (issue 53, item 6), with the facepuppet command:
#  1. run, play, export, pose and calibrate refuse an output that exists (exit 73, the file
#     named and "--force to overwrite"), before any work, and leave it byte for byte as it
#     was; --force overwrites it; run's default --out takes the next free name and says so.
#  2. --frames-out (run, play) and export's obj-seq folder refuse the frames of an earlier
#     run; --frames-out's size is said before the first frame, a warning over 1 GiB.
#  3. export --range: past the take refused before any frame (64, naming the take's frames),
#     OUT past the end clipped with a warning and the frames said.
#  4. an --input that looks like a file suggests replay:FILE (take:FILE for a .fptake).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp="$(cd "$build" && pwd)/bin/facepuppet"
pd=(--plugin-dir "$(cd "$build" && pwd)/lib/facepuppet")
data=$(cd "${FP_SHARED_DATA:-../shared/data}" && pwd)
mesh=$data/faces/ict-facekit/generic_neutral_mesh.obj
csv=$data/hands/leap-motion/three-claps_joints_mm.csv
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-no-overwrite-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
# expect STATUS CMD...: run CMD (output in $tmp/x.out), fail unless it exits STATUS
expect() { local want=$1; shift; "$@" >"$tmp/x.out" 2>&1; local got=$?
           [ $got -eq "$want" ] || { cat "$tmp/x.out"; fail "exit $got, want $want: $*"; }; }
# refused FILE CMD...: CMD exits 73 naming FILE and --force, and FILE is byte-unchanged
refused() { local file=$1; shift; cp -a "$file" "$tmp/before"
            expect 73 "$@"
            grep -qF -- "$file: exists (--force to overwrite)" "$tmp/x.out" ||
                { cat "$tmp/x.out"; fail "the refusal does not name $file and --force: $*"; }
            cmp -s "$file" "$tmp/before" || fail "$file changed though refused: $*"; }
cd "$tmp" || exit 1
run=("$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:$csv,fast=1" --duration 0.4)

# ---- 1. run ----------------------------------------------------------------------------------
"${run[@]}" -q --take-dir takes --slate clap -o run.obj >/dev/null 2>&1 || fail "run exited $?"
take=takes/clap_T001.fptake
[ -f "$take" ] || fail "no take recorded"
# --take-dir whose parents are missing: made, as mkdir -p (the take was lost: "No such file")
expect 0 "${run[@]}" -q --take-dir new/deep/takes --slate deep -o deep.obj
[ -f new/deep/takes/deep_T001.fptake ] || fail "no take in new/deep/takes: $(cat "$tmp/x.out")"
# one under a file: refused before any work, naming the option and the folder
echo "a file" >plain
expect 73 "${run[@]}" -q --take-dir plain/takes -o under.obj
grep -q "facepuppet run: --take-dir plain/takes: not a folder" "$tmp/x.out" || { cat "$tmp/x.out"; fail "run --take-dir under a file: not said"; }
[ ! -e under.obj ] || fail "a run refused for its --take-dir wrote its --out"
expect 73 "$fp" live --take-dir plain/takes --frames 1
grep -q "facepuppet live: --take-dir plain/takes: not a folder" "$tmp/x.out" || { cat "$tmp/x.out"; fail "live --take-dir under a file: not said before the window"; }
echo "stale" >old.obj
refused old.obj "${run[@]}" -q -o old.obj
# (refused before any work: no take, no frames)
expect 73 "${run[@]}" -q -o old.obj --take-dir takes
[ ! -e takes/scene1_T001.fptake ] || fail "a refused run recorded a take"
expect 0 "${run[@]}" -q -o old.obj --force
[ "$(head -c 5 old.obj)" != "stale" ] || fail "--force did not overwrite old.obj"
echo "stale" >old.pc2
refused old.pc2 "${run[@]}" -q -o new.obj --export old.pc2
[ ! -e new.obj ] || fail "a refused run wrote its --out"
expect 0 "${run[@]}" -q -o new.obj --export old.pc2 --force
[ "$(head -c 5 old.pc2)" != "stale" ] || fail "--force did not overwrite --export's file"
# the default --out: the next free name, said
echo "mine" >facepuppet-out.obj
expect 0 "${run[@]}"
grep -q "facepuppet-out.obj exists: writing facepuppet-out-1.obj instead" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "run did not say it took the next free name"; }
[ "$(cat facepuppet-out.obj)" = "mine" ] || fail "run overwrote the default facepuppet-out.obj"
[ -s facepuppet-out-1.obj ] || fail "no facepuppet-out-1.obj"
expect 0 "${run[@]}" -q
[ -s facepuppet-out-2.obj ] || fail "no facepuppet-out-2.obj the second time"
echo "run: refused, --force, next free name: ok"

# ---- 1. play, export, pose, calibrate ---------------------------------------------------------
echo "stale" >play.obj
refused play.obj "$fp" play "${pd[@]}" "$take" -o play.obj
expect 0 "$fp" play "${pd[@]}" "$take" -o play.obj --force -q
cmp -s play.obj run.obj || fail "play --force did not write the take's last frame"
echo "stale" >play.pc2
refused play.pc2 "$fp" play "${pd[@]}" "$take" --export play.pc2
echo "stale" >exp.pc2
refused exp.pc2 "$fp" export "${pd[@]}" "$take" -f pc2 -o exp.pc2
expect 0 "$fp" export "${pd[@]}" "$take" -f pc2 -o exp.pc2 --force -q
[ "$(head -c 5 exp.pc2)" != "stale" ] || fail "export --force did not overwrite"
# the default output beside the take
expect 0 "$fp" export "${pd[@]}" "$take" -f mdd -q
[ -s takes/clap_T001.mdd ] || fail "export wrote no takes/clap_T001.mdd"
refused takes/clap_T001.mdd "$fp" export "${pd[@]}" "$take" -f mdd
echo "stale" >pose.obj
refused pose.obj "$fp" pose --mesh "$mesh" --set jaw.open=0.5 -o pose.obj
expect 0 "$fp" pose --mesh "$mesh" --set jaw.open=0.5 -o pose.obj --force
[ "$(head -c 5 pose.obj)" != "stale" ] || fail "pose --force did not overwrite"
echo '{"stale": true}' >cal.json
refused cal.json "$fp" calibrate "${pd[@]}" --mesh "$mesh" --input "replay:$csv,fast=1" -o cal.json
expect 0 "$fp" calibrate "${pd[@]}" --mesh "$mesh" --input "replay:$csv,fast=1" -o cal.json --force
grep -q stale cal.json && fail "calibrate --force did not overwrite"
for c in run play export pose calibrate; do
    "$fp" $c --help | grep -q -- "--force" || fail "$c --help does not name --force"
done
echo "play, export, pose, calibrate: refused, --force: ok"
# live (where this build has the viewer): --out and --screenshot refused before the window
# opens (no display needed to see it); with --force the check passes and live goes on to the
# window (here without a display: any status but 73), the file untouched
if "$fp" live --help >/dev/null 2>&1; then
    echo "stale" >shot.png
    refused shot.png "$fp" live "${pd[@]}" --frames 1 --screenshot shot.png
    refused old.obj "$fp" live "${pd[@]}" --frames 1 -o old.obj
    env -u DISPLAY -u WAYLAND_DISPLAY "$fp" live "${pd[@]}" --frames 1 --screenshot shot.png --force \
        >"$tmp/x.out" 2>&1
    [ $? -ne 73 ] || { cat "$tmp/x.out"; fail "live --screenshot --force: still refused"; }
    "$fp" live --help | grep -q -- "--force" || fail "live --help does not name --force"
    echo "live: --out, --screenshot refused: ok"
fi

# ---- 2. folders of frames, the size estimate --------------------------------------------------
expect 0 "$fp" play "${pd[@]}" "$take" --frames-out pf
grep -Eq "play: --frames-out pf: about [0-9.]+ [kMG]B \([0-9]+ frames x 26719 vertices" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "play did not estimate --frames-out's size"; }
n=$(ls pf | wc -l)
[ "$n" -gt 0 ] || fail "play wrote no frames"
cp pf/frame_000000_*.obj first.obj
expect 73 "$fp" play "${pd[@]}" "$take" --frames-out pf
grep -q -- "--frames-out pf: holds $n files of an earlier run (frame_000000_.*--force to overwrite" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "play --frames-out's refusal"; }
expect 0 "$fp" play "${pd[@]}" "$take" --frames-out pf --force -q
expect 73 "${run[@]}" -q -o r2.obj --frames-out pf
[ ! -e r2.obj ] || fail "a refused run wrote its --out"
# a run's estimate: over 1 GiB is a warning, said before the first frame (-q or not); the
# recording is cut to its first rows so that the run itself writes a few frames only
head -5 "$csv" >short.csv
expect 0 "$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:short.csv,fast=1" --duration 100 -q \
    -o r3.obj --frames-out big
grep -q "warning: --frames-out big: about [0-9.]* GB (6001 frames x 26719 vertices.*over 1 GiB" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "run did not warn of a --frames-out over 1 GiB"; }
[ "$(ls big | wc -l)" -lt 100 ] || fail "the short recording made $(ls big | wc -l) frames"
# the same warning for a point cache beside it (fp_app_output_fits: export, run and play
# alike), with its size a frame: 12 bytes a vertex
expect 0 "$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:short.csv,fast=1" --duration 100 -q \
    -o r5.obj --export big.pc2
grep -q "warning: --export big.pc2: about 1.9 GB (6001 frames x 26719 vertices, ~321 kB a frame), over 1 GiB" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "run did not warn of an --export over 1 GiB"; }
[ "$(stat -c %s big.pc2)" -lt 100000000 ] || fail "the short recording made a point cache of $(stat -c %s big.pc2) bytes"
# no --duration: the rate a second and when it passes 1 GiB
expect 0 "$fp" run "${pd[@]}" --mesh "$mesh" --input "replay:short.csv,fast=1" -o r4.obj --frames-out big2
grep -q -- "--frames-out big2: about [0-9]* MB a second (60 frames a second x 26719 vertices.*1 GiB after [0-9]* s" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "run did not say --frames-out's rate"; }
# the estimate holds for a face that is no OBJ: its frames carry vn lines and normal indices
# (36 bytes a vertex and 17 a triangle said ~24 kB of MediaPipe's 468-vertex mask as a PLY,
# whose frames are 49 kB: a disk's room checked against half the frames' size)
mp=$data/faces/mediapipe-canonical/canonical_face_model.obj
expect 0 "$fp" run "${pd[@]}" --mesh "$mp" --input "replay:short.csv,fast=1" --duration 0.01 -q -o mask.ply
expect 0 "$fp" run "${pd[@]}" --mesh mask.ply --input "replay:short.csv,fast=1" --duration 0.05 \
    -o mask-out.ply --frames-out maskframes
said=$(grep -o -- "--frames-out maskframes: about .*, ~[0-9]* kB a frame" "$tmp/x.out" | grep -o "~[0-9]*" | tr -d '~')
[ -n "$said" ] || { cat "$tmp/x.out"; fail "no size said for the PLY face's frames"; }
real=$(wc -c <"maskframes/$(ls maskframes | head -1)")
[ $((said * 1000)) -ge "$real" ] && [ $((said * 1000)) -le $((real * 13 / 10)) ] ||
    fail "--frames-out said ~$said kB a frame, a frame holds $real bytes"
expect 0 "$fp" export "${pd[@]}" "$take" -f obj-seq -o seq -q
expect 73 "$fp" export "${pd[@]}" "$take" -f obj-seq -o seq
grep -q "seq: holds .* of an earlier run (clap_T001_000000.obj" "$tmp/x.out" || { cat "$tmp/x.out"; fail "obj-seq refusal"; }
expect 0 "$fp" export "${pd[@]}" "$take" -f obj-seq -o seq --force -q
echo "frames folders, size estimate: ok"

# ---- 3. export --range ------------------------------------------------------------------------
frames=$(ls seq | wc -l)
last=$((frames - 1))
start=$(date +%s%N)
expect 64 "$fp" export "${pd[@]}" "$take" -f pc2 -o range.pc2 --range $((frames + 5))-$((frames + 50))
grep -q "IN is past the take's last frame (the take has frames 0-$last, timecodes" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "an out-of-range --range is not refused naming the take's frames"; }
[ ! -e range.pc2 ] || fail "a refused --range wrote its output"
expect 64 "$fp" export "${pd[@]}" "$take" -f pc2 -o range.pc2 --range 9-3
grep -q "IN is after OUT" "$tmp/x.out" || { cat "$tmp/x.out"; fail "IN after OUT"; }
expect 0 "$fp" export "${pd[@]}" "$take" -f pc2 -o range.pc2 --range 10-480
grep -q "warning: --range 10-480: OUT (frame 480) is past the take's last frame (frame $last): clipped" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "a clipped --range is not warned about"; }
grep -q "exporting frames 10-$last ($((last - 9)) of the take's $frames)" "$tmp/x.out" ||
    { cat "$tmp/x.out"; fail "the clipped range's frames are not said"; }
grep -q "exported $((last - 9)) frames" "$tmp/x.out" || { cat "$tmp/x.out"; fail "the clipped export's frames"; }
expect 0 "$fp" export "${pd[@]}" "$take" -f pc2 -o range2.pc2 --range 10-20
grep -q warning "$tmp/x.out" && { cat "$tmp/x.out"; fail "a range inside the take warned"; }
echo "export --range: ok"

# ---- 4. a SPEC that looks like a file ---------------------------------------------------------
expect 64 "$fp" run "${pd[@]}" --input "$csv"
grep -qF -- "did you mean --input replay:$csv?" "$tmp/x.out" || { cat "$tmp/x.out"; fail "no replay: suggestion"; }
expect 64 "$fp" run "${pd[@]}" --input "$take,speed=2"
grep -qF -- "did you mean --input take:$take,speed=2?" "$tmp/x.out" || { cat "$tmp/x.out"; fail "no take: suggestion"; }
expect 64 "$fp" calibrate "${pd[@]}" --input foo.csv -o c2.json
grep -qF -- "did you mean --input replay:foo.csv?" "$tmp/x.out" || { cat "$tmp/x.out"; fail "calibrate: no suggestion"; }
echo "SPEC suggestion: ok"
echo "PASS"
