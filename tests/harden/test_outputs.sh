#!/usr/bin/env bash
# Outputs never half-written and plugin folders that cannot be hijacked, at the command level:
#  1. SIGKILL while `facepuppet run` writes --out over a good file (the Lee Perry-Smith head,
#     about 3 MB of OBJ): the kill is sent the moment fp_mesh_save's temporary file appears;
#     afterwards the target is the old file, intact, or a complete new one, never a part.
#  2. record= on a full disk (enospc_shim.so, an LD_PRELOAD that lets the recording have
#     FP_ENOSPC_AFTER bytes): the run says so and exits 73; the recording ends with a whole
#     line and reads back.
#  3. record= never overwrites: an existing FILE stays, FILE-1.log, FILE-2.log are taken and
#     named on stderr; force=1 overwrites.
#  4. FACEPUPPET_PLUGIN_PATH naming a world-writable folder that holds input-x.so: the
#     folder is skipped with a warning naming it and "writable by others"; `monitor x` exits
#     78; the same folder at 0755 is searched.
#  5. a FIFO (and, as root, a device node) given as --out of run, pose and calibrate: 73 before
#     the work, the FIFO kept; a symbolic link written through (the link kept); a FIFO given
#     as an input (info, replay:, a take in `takes`' folder): refused at once, never waited on.
#  6. a file system that refuses modes (vfat, exFAT: the shim's fchmod fails with EPERM): run
#     --out, pose --out, calibrate --out and export -f pc2 still write their files whole.
# Run from the repository root by ctest (FP_BUILD_DIR, FP_SHARED_DATA).
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
data=${FP_SHARED_DATA:-../shared/data}
fp=$build/bin/facepuppet
mesh=$data/faces/lee-perry-smith/LeePerrySmith.obj
rec=$data/hands/leap-motion/grab_joints_mm.csv
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-outputs-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
vertices() { "$fp" info "$1" 2>/dev/null | sed -n 's/^ *vertices *\([0-9]*\).*/\1/p'; }

# ---- 1. SIGKILL during --out -----------------------------------------------------------
out=$tmp/kill/face.obj
mkdir -p "$tmp/kill"
"$fp" run --quiet --mesh "$mesh" --input "replay:$rec,fast=1" --duration 0.2 --out "$out" \
    >/dev/null 2>"$tmp/first.err" || { cat "$tmp/first.err"; fail "the first run failed"; }
nv=$(vertices "$out")
[[ -n $nv && $nv -gt 0 ]] || fail "the first --out does not load"
landed=0 finished=0
for attempt in $(seq 1 12); do
    old=$(md5sum <"$out")
    "$fp" run --quiet --mesh "$mesh" --input "replay:$rec,fast=1" --duration "0.$attempt" \
        --out "$out" --force >/dev/null 2>&1 &
    pid=$!
    hit=0
    while kill -0 $pid 2>/dev/null; do
        for f in "$tmp"/kill/.face.obj.*; do
            if [[ -e $f ]]; then kill -9 $pid 2>/dev/null && hit=1; break 2; fi
        done
    done
    wait $pid 2>/dev/null
    rc=$?
    if (( hit && rc == 137 )); then landed=$((landed + 1)); else finished=$((finished + 1)); fi
    now=$(md5sum <"$out")
    if [[ $now != "$old" ]]; then
        v=$(vertices "$out")
        [[ $v == "$nv" ]] || fail "attempt $attempt (killed: $hit, exit $rc): $out is neither the old file nor a whole new one (vertices '$v')"
    fi
    rm -f "$tmp"/kill/.face.obj.*
    (( landed >= 3 )) && break
done
echo "1. SIGKILL during --out: $landed kills landed during the write, $finished runs ended first; $out always whole"
(( landed >= 1 )) || fail "no kill landed during the write in 12 attempts"

# ---- 2. record= on a full disk ---------------------------------------------------------
shim=$build/tests/enospc_shim.so
if [[ -f $shim ]]; then
    log=$tmp/full/rec.log
    mkdir -p "$tmp/full"
    FP_ENOSPC_MATCH=/full/rec.log FP_ENOSPC_AFTER=30000 LD_PRELOAD=$shim \
        "$fp" run --quiet --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" \
        --input "replay:$rec,fast=1,record=$log" --out "$tmp/full/out.obj" >"$tmp/full.out" 2>"$tmp/full.err"
    rc=$?
    size=$(stat -c %s "$log" 2>/dev/null || echo 0)
    [[ $rc == 73 ]] || fail "disk full during record=: exit $rc, expected 73: $(cat "$tmp/full.err")"
    grep -q "rec.log.*No space left on device" "$tmp/full.err" || fail "disk full: no message naming the recording and the cause"
    (( size > 0 && size <= 30000 )) || fail "disk full: the recording has $size bytes (at most 30000 fit)"
    [[ $(tail -c 1 "$log" | od -An -c | tr -d ' ') == '\n' ]] || fail "disk full: the recording ends inside a line"
    "$fp" info "$log" >"$tmp/full.info" 2>&1 || fail "disk full: the recording does not read back: $(cat "$tmp/full.info")"
    echo "2. record= on a full disk: exit $rc, $size of 30000 bytes kept, $(grep -c . "$log") whole lines; stderr:"
    grep -i "record" "$tmp/full.err" | head -3
else
    fail "no $shim (build the test_outputs dependencies)"
fi

# ---- 3. record= never overwrites --------------------------------------------------------
mkdir -p "$tmp/rec"
echo precious >"$tmp/rec/take.log"
for n in 1 2; do
    "$fp" run --quiet --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" \
        --input "replay:$rec,fast=1,record=$tmp/rec/take.log" --duration 0.2 \
        --out "$tmp/rec/out.obj" --force >/dev/null 2>"$tmp/rec.err" || fail "record run $n failed: $(cat "$tmp/rec.err")"
    grep -q "recording to $tmp/rec/take-$n.log" "$tmp/rec.err" || fail "record run $n did not say it records to take-$n.log: $(cat "$tmp/rec.err")"
    head -1 "$tmp/rec/take-$n.log" 2>/dev/null | grep -q "^# facepuppet-eventlog 1" || fail "take-$n.log is not an event log"
done
[[ $(cat "$tmp/rec/take.log") == precious ]] || fail "record= overwrote an existing file"
"$fp" run --quiet --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" \
    --input "replay:$rec,fast=1,record=$tmp/rec/take.log,force=1" --duration 0.2 \
    --out "$tmp/rec/out.obj" --force >/dev/null 2>"$tmp/rec.err" || fail "force=1 run failed: $(cat "$tmp/rec.err")"
head -1 "$tmp/rec/take.log" | grep -q "^# facepuppet-eventlog 1" || fail "force=1 did not overwrite take.log"
[[ ! -e $tmp/rec/take-3.log ]] || fail "force=1 took a new name"
echo "3. record= never overwrites: take.log kept, take-1.log and take-2.log taken and named; force=1 overwrote"

# ---- 4. a world-writable plugin folder ---------------------------------------------------
pdir=$tmp/plugins
mkdir -p "$pdir"
cp "$build/lib/facepuppet/input-replay.so" "$pdir/input-x.so"
chmod 0777 "$pdir"
FACEPUPPET_PLUGIN_PATH=$pdir "$fp" monitor x >"$tmp/mon.out" 2>"$tmp/mon.err"
rc=$?
[[ $rc == 78 ]] || fail "monitor x with a world-writable plugin folder: exit $rc, expected 78"
grep -q "$pdir.*writable by others" "$tmp/mon.err" || fail "no warning naming $pdir and 'writable by others': $(cat "$tmp/mon.err")"
FACEPUPPET_PLUGIN_PATH=$pdir "$fp" plugins >"$tmp/list0777.out" 2>&1
chmod 0755 "$pdir"
FACEPUPPET_PLUGIN_PATH=$pdir "$fp" plugins >"$tmp/list0755.out" 2>&1
grep -q "input-x.so" "$tmp/list0777.out" && fail "plugins lists input-x.so from the world-writable folder"
grep -q "input-x.so" "$tmp/list0755.out" || fail "plugins does not list input-x.so from the same folder at 0755: $(cat "$tmp/list0755.out")"
echo "4. world-writable plugin folder: monitor x exit $rc; stderr:"
grep -m1 "writable" "$tmp/mon.err"

# ---- 5. what is not a regular file: never replaced, never waited on -----------------------
sp=$tmp/special
mkdir -p "$sp/takes"
mkfifo "$sp/fifo.obj" "$sp/fifo.json" "$sp/takes/x_T001.fptake"
ict=$data/faces/ict-facekit/generic_neutral_mesh.obj
for cmd in "run --quiet --mesh $ict --input replay:$rec,fast=1 --duration 0.2 --out $sp/fifo.obj" \
           "pose --mesh $ict --set jaw.open=0.3 --out $sp/fifo.obj" \
           "calibrate --input replay:$rec,fast=1 --out $sp/fifo.json"; do
    timeout 60 "$fp" $cmd >/dev/null 2>"$tmp/sp.err"
    rc=$?
    [[ $rc == 73 ]] || fail "'$cmd' over a FIFO: exit $rc, expected 73: $(cat "$tmp/sp.err")"
    grep -q "fifo.*not a regular file" "$tmp/sp.err" || fail "'$cmd': no message naming the FIFO: $(cat "$tmp/sp.err")"
done
[[ -p $sp/fifo.obj && -p $sp/fifo.json ]] || fail "a FIFO given as --out was replaced"
if mknod "$sp/dev.obj" c 1 3 2>/dev/null; then # (root only: a device node, /dev/null's numbers)
    "$fp" run --quiet --mesh "$ict" --input "replay:$rec,fast=1" --duration 0.2 --out "$sp/dev.obj" \
        >/dev/null 2>&1
    rc=$?
    [[ $rc == 73 && -c $sp/dev.obj ]] || fail "--out over a device node: exit $rc, node kept: $([[ -c $sp/dev.obj ]] && echo yes || echo no)"
    devnode="a device node kept (73)"
else
    devnode="no device node (not root)"
fi
# a symbolic link is written through: the link stays, its file (existing or not) is written
echo old >"$sp/real.obj"
ln -s real.obj "$sp/link.obj"
ln -s new.obj "$sp/dangling.obj"
for l in link dangling; do
    "$fp" run --quiet --mesh "$ict" --input "replay:$rec,fast=1" --duration 0.2 --out "$sp/$l.obj" --force \
        >/dev/null 2>"$tmp/sp.err" || fail "--out $l.obj: $(cat "$tmp/sp.err")"
    [[ -L $sp/$l.obj ]] || fail "--out $l.obj replaced the symbolic link"
done
[[ $(vertices "$sp/real.obj") == 26719 ]] || fail "--out link.obj did not write real.obj"
[[ $(vertices "$sp/new.obj") == 26719 ]] || fail "--out dangling.obj did not write new.obj"
# inputs: a FIFO is refused at once (66), never opened for reading and waited on
timeout 20 "$fp" info "$sp/fifo.obj" >/dev/null 2>&1
rc=$?
[[ $rc == 66 ]] || fail "info on a FIFO: exit $rc, expected 66 (124: it waited)"
timeout 20 "$fp" run --quiet --mesh "$ict" --input "replay:$sp/fifo.json" --out "$sp/o.obj" >/dev/null 2>&1
rc=$?
[[ $rc == 66 ]] || fail "replay: of a FIFO: exit $rc, expected 66 (124: it waited)"
timeout 20 "$fp" takes "$sp/takes" >"$tmp/takes.out" 2>&1
rc=$?
[[ $rc == 0 ]] && grep -q "not a regular file" "$tmp/takes.out" ||
    fail "takes over a folder holding a FIFO: exit $rc (124: it waited): $(cat "$tmp/takes.out")"
echo "5. FIFOs as --out of run, pose, calibrate: 73, kept; $devnode; links written through; FIFO inputs 66"

# ---- 6. no Unix modes (vfat): saves still made ------------------------------------------
if [[ -f $shim ]]; then
    nm=$tmp/nomodes
    mkdir -p "$nm"
    for cmd in "run --quiet --mesh $ict --input replay:$rec,fast=1 --duration 0.3 --out $nm/run.obj --take-dir $nm" \
               "pose --mesh $ict --set jaw.open=0.3 --out $nm/pose.obj" \
               "calibrate --input replay:$rec,fast=1 --out $nm/cal.json"; do
        FP_FCHMOD_EPERM=1 LD_PRELOAD=$shim timeout 120 "$fp" $cmd >/dev/null 2>"$tmp/nm.err" ||
            fail "'$cmd' where fchmod fails (EPERM): exit $?: $(cat "$tmp/nm.err")"
    done
    [[ $(vertices "$nm/run.obj") == 26719 && $(vertices "$nm/pose.obj") == 26719 ]] ||
        fail "run/pose --out where fchmod fails: not the whole mesh"
    grep -q '"mm_per_unit"' "$nm/cal.json" 2>/dev/null || fail "calibrate where fchmod fails: no file"
    take=$(ls "$nm"/*.fptake 2>/dev/null | head -1)
    if [[ -n $take ]]; then
        FP_FCHMOD_EPERM=1 LD_PRELOAD=$shim "$fp" export "$take" -f pc2 -o "$nm/t.pc2" >/dev/null 2>"$tmp/nm.err" ||
            fail "export pc2 where fchmod fails: exit $?: $(cat "$tmp/nm.err")"
        [[ -s $nm/t.pc2 ]] || fail "export pc2 where fchmod fails: no file"
    else
        fail "run --take-dir where fchmod fails: no take"
    fi
    [[ -z $(find "$nm" -name '.*' -type f) ]] || fail "temporary files left where fchmod fails"
    echo "6. fchmod refused (EPERM, as on vfat): run, pose, calibrate, export pc2 saved whole"
fi

if (( fails )); then echo "$fails failure(s)"; exit 1; fi
echo "ok"
