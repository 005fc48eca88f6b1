#!/usr/bin/env bash
# test_bench_trace.sh FACEPUPPET: `facepuppet bench --case frame --trace FILE.csv` (see
# CMakeLists.txt). Run from the source root, with ../shared/data beside it (FP_SHARED_DATA).
set -u
fp=$1
py=/usr/bin/python3
[ -x "$py" ] || py=python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/o" # where the traces go (the logs stay in $tmp)
fail() { echo "FAIL: $*" >&2; exit 1; }

# 1. errors before any work, nothing written
"$fp" bench --case frame --trace "$tmp/o/no/such/dir/t.csv" >"$tmp/out" 2>"$tmp/err"
rc=$?
[ $rc = 73 ] || fail "--trace into a missing folder: exit $rc, expected 73"
grep -q "t.csv: cannot create a file beside it" "$tmp/err" || fail "no message naming the file: $(cat "$tmp/err")"
grep -q "^frame" "$tmp/out" && fail "the frame case ran before the trace's folder was checked"
"$fp" bench --case table1 --trace "$tmp/o/t.csv" >/dev/null 2>"$tmp/err"
rc=$?
[ $rc = 64 ] || fail "--trace with --case table1: exit $rc, expected 64"
grep -q "records the frame case" "$tmp/err" || fail "no reason for --case table1: $(cat "$tmp/err")"
"$fp" bench --plot "$tmp/o/f.png" --trace "$tmp/o/t.csv" >/dev/null 2>&1
rc=$?
[ $rc = 64 ] || fail "--trace with --plot: exit $rc, expected 64"
"$fp" bench --case frame --subdivide 4 >"$tmp/out" 2>"$tmp/err"
rc=$?
[ $rc = 64 ] || fail "--subdivide 4: exit $rc, expected 64"
grep -q "levels 1 to 3" "$tmp/err" || fail "no reason for --subdivide 4: $(cat "$tmp/err")"
grep -q "^frame" "$tmp/out" && fail "the frame case ran with --subdivide 4"
"$fp" bench --case table1 --subdivide 1 >/dev/null 2>"$tmp/err"
rc=$?
[ $rc = 64 ] || fail "--subdivide with --case table1: exit $rc, expected 64"
[ -z "$(ls -A "$tmp/o")" ] || fail "files left behind by the failed calls: $(ls -A "$tmp/o")"
# an existing trace is refused before any work (73, named, untouched) unless --force
echo "mine" >"$tmp/mine.csv"
"$fp" bench --case frame --trace "$tmp/mine.csv" >"$tmp/out" 2>"$tmp/err"
rc=$?
[ $rc = 73 ] || fail "--trace onto an existing file: exit $rc, expected 73"
grep -q -- "--trace $tmp/mine.csv: exists (--force to overwrite)" "$tmp/err" ||
    fail "no message naming the existing trace: $(cat "$tmp/err")"
grep -q "^frame" "$tmp/out" && fail "the frame case ran before the existing trace was refused"
[ "$(cat "$tmp/mine.csv")" = mine ] || fail "the refused trace was changed"
"$fp" bench --force --case table1 --trace "$tmp/mine.csv" >/dev/null 2>"$tmp/err"
rc=$?
[ $rc = 64 ] || fail "--force --case table1 --trace: exit $rc, expected 64 (--trace's case), not --force refused"
grep -q "records the frame case" "$tmp/err" || fail "--force is not an option of bench: $(cat "$tmp/err")"

# 2. a real run: one row per frame of each mesh, agreeing with the table it printed
"$fp" bench --case frame --trace "$tmp/o/t.csv" >"$tmp/out" 2>"$tmp/err" ||
    fail "bench --case frame --trace exited $?: $(tail -3 "$tmp/err")"
grep -q "wrote $tmp/o/t.csv" "$tmp/err" || fail "no 'wrote' line: $(tail -2 "$tmp/err")"
ls -A "$tmp/o" | grep -q '^\.t\.csv\.' && fail "a temporary file was left behind"
"$py" - "$tmp/o/t.csv" "$tmp/out" <<'PY' || fail "the trace does not match the run's table"
import csv, math, re, sys
header = ("mesh,frame,frame_ms,events_ms,hands_ms,distances_ms,mapping_ms,solve_ms,evaluate_ms,"
          "shape_ms,commit_ms,contact_ms,contact_worker_wait_ms,cpu_wait_ms,cpu,active,engaged,"
          "committed,refactored,control_vectors,pairs,guard_substeps,contact_t,contact_pairs,"
          "contact_held,contact_checks,contact_moved,contact_node_pairs,contact_leaf_pairs,"
          "contact_tested,contact_certified,skipped_after")
lines = open(sys.argv[1]).read().splitlines()
assert lines[0] == header, f"header: {lines[0]}"
rows = list(csv.DictReader(lines))
table = {}
for line in open(sys.argv[2]):
    m = re.match(r"frame (\S+)\s+(\d+) vertices, .*?, (\d+) frames in [\d.]+ s \((\d+) skipped"
                 r".*?, (\d+) deforming, (\d+) commits", line)
    if m:
        table[m.group(1)] = [int(g) for g in m.groups()[1:]]
assert set(table) == {"ict", "ict-subdiv3"}, f"meshes in the table: {sorted(table)}"
stages = ["events_ms", "hands_ms", "distances_ms", "mapping_ms", "solve_ms", "evaluate_ms", "shape_ms",
          "commit_ms"]
for mesh, (nv, frames, skipped, deforming, commits) in table.items():
    rs = [r for r in rows if r["mesh"] == mesh]
    assert len(rs) == frames, f"{mesh}: {len(rs)} rows, the table says {frames} frames"
    assert [int(r["frame"]) for r in rs] == list(range(frames)), f"{mesh}: frame numbers"
    assert sum(int(r["skipped_after"]) for r in rs) == skipped, f"{mesh}: skipped"
    assert sum(r["active"] == "1" for r in rs) == deforming, f"{mesh}: deforming"
    assert sum(r["committed"] == "1" for r in rs) == commits, f"{mesh}: commits"
    for r in rs:
        f = float(r["frame_ms"])
        assert math.isfinite(f) and f > 0, f"{mesh} frame {r['frame']}: frame_ms {f}"
        for s in stages + ["contact_ms"]:  # each stage is a part of the frame
            assert 0 <= float(r[s]) <= f + 1e-3, f"{mesh} frame {r['frame']}: {s} {r[s]} > {f}"
        # the stages are disjoint parts of the frame: their sum cannot pass it
        parts = sum(float(r[s]) for s in stages + ["contact_ms"])
        assert parts <= f + 1e-3, f"{mesh} frame {r['frame']}: the stages add up to {parts} > {f}"
        t = float(r["contact_t"])
        assert 0 <= t <= 1, f"{mesh} frame {r['frame']}: contact_t {t}"
        moved, checks = int(r["contact_moved"]), int(r["contact_checks"])
        assert moved <= nv, f"{mesh} frame {r['frame']}: {moved} moved of {nv}"
        assert (checks > 1) >= (t < 1), f"{mesh} frame {r['frame']}: scaled back after {checks} check"
        walk = [int(r[c]) for c in ("contact_node_pairs", "contact_leaf_pairs", "contact_tested",
                                    "contact_certified")]
        assert checks > 0 or walk == [0, 0, 0, 0], f"{mesh} frame {r['frame']}: a walk without a check"
        if r["active"] == "0":
            assert int(r["pairs"]) == 0 and r["committed"] == "0", f"{mesh} frame {r['frame']}: idle frame"
    # the session's guard walks its hierarchy on every face: over the drags, node pairs, leaf
    # pairs and exact tests (the counts the table's "contact walk" line gives medians of)
    for c in ("contact_node_pairs", "contact_leaf_pairs", "contact_tested"):
        assert sum(int(r[c]) for r in rs) > 0, f"{mesh}: no {c} in any frame"
walks = [l for l in open(sys.argv[2]) if l.startswith("  contact walk: a check reaches ")]
assert len(walks) == len(table), f"{len(walks)} 'contact walk' lines for {len(table)} meshes"
print("trace:", {m: len([r for r in rows if r["mesh"] == m]) for m in table}, "rows")
PY

# 3. --subdivide 1 --every-frame: the ICT face and its first subdivision (with the ICT face's
# rig carried onto it), in the table and the trace; every frame of the recording stepped on its own clock, so the 105k face (whose slow
# frames the paced loop of 2. would skip periods after) has as many frames as the ICT face, and
# none skipped
"$fp" bench --case frame --quick --subdivide 1 --every-frame --trace "$tmp/o/t1.csv" >"$tmp/out1" 2>"$tmp/err" ||
    fail "bench --case frame --subdivide 1 --every-frame exited $?: $(tail -3 "$tmp/err")"
n_ict=$(sed -n 's/^frame ict  *26719 vertices, .*, \([0-9]*\) frames in .*(every one stepped; .*/\1/p' "$tmp/out1")
n_sub=$(sed -n 's/^frame ict-subdiv1 *105569 vertices, .*, \([0-9]*\) frames in .*(every one stepped; .*/\1/p' "$tmp/out1")
[ -n "$n_ict" ] && [ "$n_ict" -gt 100 ] && [ "$n_ict" = "$n_sub" ] ||
    fail "--every-frame: frames '$n_ict' (ict) and '$n_sub' (ict-subdiv1), expected the same, every one stepped: $(grep '^frame' "$tmp/out1")"
awk -F, 'NR > 1 && $NF != 0 { bad = 1 } END { exit bad }' "$tmp/o/t1.csv" ||
    fail "--every-frame: a frame's skipped_after is not 0"
grep -q "^frame ict-subdiv1 *105569 vertices" "$tmp/out1" || fail "no ict-subdiv1 row of 105569 vertices: $(grep '^frame' "$tmp/out1")"
grep -q "^frame ict-subdiv3" "$tmp/out1" && fail "--subdivide 1 ran level 3 too"
grep -A1 "^frame ict-subdiv1" "$tmp/out1" | grep -q "rig: the ICT face's, carried through each subdivision" ||
    fail "the 105k face does not carry the ICT face's rig: $(grep -A1 '^frame ict-subdiv1' "$tmp/out1")"
cut -d, -f1 "$tmp/o/t1.csv" | sort -u | tr '\n' ' ' | grep -qx "ict ict-subdiv1 mesh " ||
    fail "the trace's meshes: $(cut -d, -f1 "$tmp/o/t1.csv" | sort -u | tr '\n' ' ')"
exit 0
