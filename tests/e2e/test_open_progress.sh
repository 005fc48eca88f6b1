#!/usr/bin/env bash
# test_open_progress.sh FACEPUPPET: `facepuppet run` (and `info`) show a face's opening on a terminal
# (fp_app_open_progress: one status line rewritten per step, cleared when the session is open)
# and nowhere else. The terminal is a pseudo-terminal made by script(1) (util-linux).
set -u
fp=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v script >/dev/null || { echo "SKIP: no script(1)"; exit 77; }
esc=$(printf '\033')
cr=$(printf '\r')

# 1. on a terminal: each step's line, each one erasing the last, the last erased before the
#    run's own header line
script -qec "$fp run --out $tmp/a.obj" "$tmp/tty.txt" >/dev/null 2>&1 || fail "run on a terminal failed: $(tail -3 "$tmp/tty.txt")"
for step in "loading generic_neutral_mesh.obj (3 MiB)" "indexing 26719 vertices" \
            "building the contact guard over" "loading the mapping and 1 input"; do
    grep -qF "${cr}${esc}[Kfacepuppet run: opening: $step" "$tmp/tty.txt" ||
        fail "no status line for '$step': $(head -c 600 "$tmp/tty.txt" | cat -v)"
done
# (an opening of a second or more is said in its place first: "opened in N s", on a
# loaded machine)
grep -qF "loading the mapping and 1 input ...${cr}${esc}[Kfacepuppet run: ../shared" "$tmp/tty.txt" ||
grep -qF "loading the mapping and 1 input ...${cr}${esc}[Kfacepuppet run: /" "$tmp/tty.txt" ||
grep -qF "loading the mapping and 1 input ...${cr}${esc}[Kfacepuppet run: opened in " "$tmp/tty.txt" ||
    fail "the status line was not erased before the run's header: $(head -c 800 "$tmp/tty.txt" | cat -v)"
grep -qF "${cr}${esc}[Kfacepuppet run: writing: $tmp/a.obj (26719 vertices) ...${cr}${esc}[K" "$tmp/tty.txt" ||
    fail "no erased status line while the mesh was written: $(tail -c 600 "$tmp/tty.txt" | cat -v)"
[ -s "$tmp/a.obj" ] || fail "no output mesh"

# 2. --quiet on a terminal, and stderr on a pipe: no status line (opening or writing)
script -qec "$fp run -q --out $tmp/b.obj" "$tmp/quiet.txt" >/dev/null 2>&1 || fail "run -q failed"
grep -qE "opening:|writing:" "$tmp/quiet.txt" && fail "--quiet printed a status line"
"$fp" run --out "$tmp/c.obj" 2>"$tmp/pipe.txt" >/dev/null || fail "run on a pipe failed"
grep -qE "opening:|writing:" "$tmp/pipe.txt" && fail "a pipe got the terminal's status line"
grep -q "facepuppet run: .*26719 vertices" "$tmp/pipe.txt" || fail "no header on the pipe"
cmp -s "$tmp/a.obj" "$tmp/c.obj" || fail "the terminal's run wrote another mesh than the pipe's"

# 3. a command that loads a face without a session (info): the same line, erased before its
#    output; none on a pipe
face=../shared/data/faces/ict-facekit/generic_neutral_mesh.obj
script -qec "$fp info $face" "$tmp/info.txt" >/dev/null 2>&1 || fail "info on a terminal failed"
grep -qF "${cr}${esc}[Kfacepuppet info: opening: loading generic_neutral_mesh.obj (3 MiB) ...${cr}${esc}[K$face" \
    "$tmp/info.txt" || fail "info: no erased status line before its output: $(head -c 400 "$tmp/info.txt" | cat -v)"
"$fp" info "$face" >"$tmp/info.out" 2>"$tmp/info.err" || fail "info on a pipe failed"
[ -s "$tmp/info.err" ] && fail "info on a pipe wrote to stderr: $(cat "$tmp/info.err")"
grep -q "vertices  26719" "$tmp/info.out" || fail "info: no vertex count"

# 5. a warning while the status line is shown (a stray vertex, said while the face opens): the
#    status line is erased before it, not run into ("... ...facepuppet: session: ..."), and
#    drawn again after it
{ cat ../shared/data/faces/mediapipe-canonical/canonical_face_model.obj; echo "v 1000 1000 1000"; } >"$tmp/stray.obj"
script -qec "$fp run --rig none --mesh $tmp/stray.obj --input replay:../shared/data/hands/leap-motion/grab_joints_mm.csv,fast=1 --duration 0.2 --out $tmp/s.obj" "$tmp/warn.txt" >/dev/null 2>&1 ||
    fail "run of stray.obj on a terminal failed: $(tail -c 400 "$tmp/warn.txt" | cat -v)"
grep -qF "vertices are in no triangle" "$tmp/warn.txt" || fail "no stray-vertex warning: $(head -c 600 "$tmp/warn.txt" | cat -v)"
grep -qF " ...facepuppet: session:" "$tmp/warn.txt" &&
    fail "a warning ran into the status line: $(head -c 800 "$tmp/warn.txt" | cat -v)"
grep -qF "${cr}${esc}[Kfacepuppet: session: $tmp/stray.obj: 1 of " "$tmp/warn.txt" ||
    fail "the status line was not erased before the warning: $(head -c 800 "$tmp/warn.txt" | cat -v)"

# 4. live (where built, with Xvfb): the viewer draws the steps in its window and still calls
#    the caller's callback, so the terminal gets the same status lines
if command -v xvfb-run >/dev/null && "$fp" live --help >/dev/null 2>&1; then
    xvfb-run -a -s "-screen 0 640x480x24" script -qec "$fp live --frames 2" "$tmp/live.txt" >/dev/null 2>&1 ||
        fail "live on a terminal failed: $(tail -c 400 "$tmp/live.txt" | cat -v)"
    grep -qF "${cr}${esc}[Kfacepuppet live: opening: building the contact guard over" "$tmp/live.txt" ||
        fail "live: no status line: $(head -c 400 "$tmp/live.txt" | cat -v)"
else
    echo "live not built or no xvfb-run: part 4 skipped"
fi
exit 0
