#!/bin/bash
# Two hands' rows in either order (step_arrive.c: the bring-in's samples, kept per hand): one
# performance, a left hand held still beside the grab recording's right hand (played forward
# and back three times: 2244 frames, 4488 rows), written with the left hand's row first in
# every frame and then second. Row order within a frame means nothing, so each placement must
# deform the MediaPipe face the same way (anchored) in both files:
#  1. by its whole range (the replay's bring-in, fp_arrive_bring_in: over 4096 samples, every
#     k-th is read): before, every 2nd row of all was read, so the left-first file was read as
#     the still left hand alone: "the recording's hands never move", held 25 mm out, 0 of 468
#     vertices moved (the right-first file: 446 moved, max 72.2 mm);
#  2. placed as it arrives (workspace=0, the live bring-in on at most 64 of the samples so far):
#     before, at an even stride every sample read was one hand's: 207 frames deforming, max
#     54 mm against 185 and 72.2 mm; now 110 and 63.5 mm both.
# Usage: test_two_hands_order.sh BUILD_DIR. Exit 77 (skipped) without python3 or the data.
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${1:?usage: test_two_hands_order.sh BUILD_DIR}
data=${FP_SHARED_DATA:-../shared/data}
mesh=$data/faces/mediapipe-canonical/canonical_face_model.obj
grab=$data/hands/leap-motion/grab_joints_mm.csv
[ -f "$grab" ] && [ -f "$mesh" ] || { echo "no $data: skipped"; exit 77; }
command -v python3 >/dev/null || { echo "no python3: skipped"; exit 77; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-two-hands-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

python3 - "$grab" "$tmp" <<'EOF' || fail "making the two-hand recordings"
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
head, right = rows[0], [r for r in rows[1:] if r[3] == "right"]
left = list(right[0])                 # the right hand's first pose, mirrored, held still
left[2], left[3] = "99", "left"
for i, c in enumerate(head):
    if c.endswith("_x") or c.endswith("_nx"):
        left[i] = "%.4f" % -float(left[i])
seq = []
for k in range(6):                    # forward and back: no jump between the passes
    seq += right if k % 2 == 0 else right[::-1]
for name, left_first in (("leftfirst", True), ("rightfirst", False)):
    with open(f"{sys.argv[2]}/{name}_joints_mm.csv", "w", newline="") as out:
        w = csv.writer(out)
        w.writerow(head)
        for i, r in enumerate(seq):
            t = str(1000000 + 9000 * i)
            a, b = [str(i), t] + left[2:], [str(i), t] + r[2:]
            for row in ((a, b) if left_first else (b, a)):
                w.writerow(row)
EOF

fp=("$build/bin/facepuppet" run --plugin-dir "$build/lib/facepuppet" -q --mesh "$mesh" --force)
# summ NAME: the summary line without its timing
summ() { grep '^frames' "$tmp/$1.out" | sed -E 's/; update median [^;]*//; s/; wrote .*//'; }
for keys in "" ",workspace=0"; do
    for order in leftfirst rightfirst; do
        "${fp[@]}" --input "replay:$tmp/${order}_joints_mm.csv,fast=1$keys" --out "$tmp/$order.obj" \
            >"$tmp/$order.out" 2>&1 || { cat "$tmp/$order.out"; fail "run on $order$keys"; }
        ! grep -q "hands never move" "$tmp/$order.out" ||
            fail "$order$keys: its right hand moves, yet: $(grep 'hands never move' "$tmp/$order.out")"
    done
    l=$(summ leftfirst) r=$(summ rightfirst)
    echo "placement ${keys:-by the whole range}: left row first: $l"
    echo "placement ${keys:-by the whole range}: right row first: $r"
    [ -n "$l" ] || fail "no summary$keys"
    [ "$l" = "$r" ] || fail "the two row orders deform the face differently$keys"
    case $l in *"vertices moved 0 "*) fail "nothing moved$keys" ;; esac
done
echo "PASS: two hands' rows in either order place and deform the same"
