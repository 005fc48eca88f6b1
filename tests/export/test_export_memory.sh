#!/usr/bin/env bash
# A glTF export that cannot be finished is refused before the frames, or stopped as soon as
# they show it, never after playing the whole take (the audit's `--resample 2000` ran out of
# memory only at the end, 7467 frames x 35130 values, after 15.7 s of play):
#  1. more frames than a glTF export compresses (FP_EXPORT_GLTF_MAX_FRAMES, 46340): 64 before
#     any frame, naming the limit;
#  2. under `ulimit -v` 3 GB, --resample 2000 of the three-claps take on the ICT face: stopped
#     while playing, before the take's last frame, exit 70, nothing written (not under ASan,
#     whose shadow memory ulimit -v does not leave room for).
# SPDX-License-Identifier: GPL-3.0-or-later
set -uo pipefail
build=${FP_BUILD_DIR:-build}
fp="$build/bin/facepuppet"
pd=(--plugin-dir "$build/lib/facepuppet")
data=${FP_SHARED_DATA:-../shared/data}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-export-mem-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$fp" run "${pd[@]}" --input "replay:$data/hands/leap-motion/three-claps_joints_mm.csv,fast=1,loop=1" \
    --duration 5 --take-dir "$tmp/takes" --slate mem -q -o "$tmp/run.obj" >"$tmp/run.out" 2>&1 ||
    { cat "$tmp/run.out"; fail "run exited $?"; }
take="$tmp/takes/mem_T001.fptake"

# 1. 5 s at 10000 fps: 50001 frames
"$fp" export "${pd[@]}" "$take" --format glb --resample 10000 --out "$tmp/cap.glb" >"$tmp/cap.out" 2>&1
rc=$?
[ $rc -eq 64 ] || { cat "$tmp/cap.out"; fail "--resample 10000: exit $rc, want 64"; }
grep -q "export: .*cap.glb: 50001 frames: a glTF export holds at most 46340 (a smaller --resample or --range); nothing written" "$tmp/cap.out" ||
    { cat "$tmp/cap.out"; fail "--resample 10000: not refused before the frames, naming the limit"; }
grep -q "engine:" "$tmp/cap.out" && { cat "$tmp/cap.out"; fail "--resample 10000: frames were played"; }
[ ! -e "$tmp/cap.glb" ] || fail "--resample 10000: a file was written"
echo "50001 frames: refused before any frame, 64"

# 2. the finish's memory, known from the frames played so far
if [ -n "${ASAN_OPTIONS:-}" ]; then
    echo "SKIP (memory): a sanitizer build"
else
    (ulimit -v 3000000; "$fp" export "${pd[@]}" "$take" --format glb --resample 2000 --range 0-224 \
        --out "$tmp/big.glb") >"$tmp/big.out" 2>&1
    rc=$?
    [ $rc -eq 70 ] || { cat "$tmp/big.out"; fail "--resample 2000 under ulimit -v: exit $rc, want 70"; }
    line=$(grep "stopped before it" "$tmp/big.out") ||
        { cat "$tmp/big.out"; fail "--resample 2000: no early stop said"; }
    frames=$(sed -E 's/.*morph targets of ([0-9]+) frames.*/\1/' <<<"$line")
    at=$(sed -E 's/.*moved by frame ([0-9]+)\).*/\1/' <<<"$line")
    [ "$at" -lt "$frames" ] || { echo "$line"; fail "stopped at frame $at of $frames: not before the end"; }
    grep -q "nothing written" <<<"$line" || fail "the stop does not say nothing was written"
    [ ! -e "$tmp/big.glb" ] || fail "--resample 2000: a file was written"
    echo "--resample 2000 under ulimit -v 3 GB: stopped at frame $at of $frames, 70"
fi
echo PASS
