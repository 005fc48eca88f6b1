# Sourced by the deterministic live-against-replay tests (test_held_pinch.sh,
# test_live_claps.sh): with $build, $mesh, $tmp and fail() set, `run NAME CSV KEYS` replays CSV
# (`replay:CSV,fast=1KEYS`, e.g. KEYS ",workspace=0": the live placement rule) on the face and
# sets $moved and $max (mm) from the run's summary line.
# SPDX-License-Identifier: GPL-3.0-or-later
fp=("$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" -q --mesh "$mesh" --force)
summary() { sed -n 's/.*vertices moved \([0-9]*\) of [0-9]*; displacement mean [^;]* max \([0-9.e+-]*\) mm.*/\1 \2/p' "$1"; }
# run NAME CSV KEYS: sets moved, max
run() {
    "${fp[@]}" --input "replay:$2,fast=1$3" --out "$tmp/$1.obj" >"$tmp/$1.out" 2>"$tmp/$1.err" ||
        { cat "$tmp/$1.err"; fail "run $1"; }
    read -r moved max < <(summary "$tmp/$1.out")
    [ -n "${max:-}" ] || { cat "$tmp/$1.out"; fail "no summary for $1"; }
}
