#!/bin/sh
# The take's line at the top right (ui/viewer/takes.c fp_vtakes_draw) never runs over the
# HUD's badge: live records a take (T) with a long slate in a 320x240 window, and in the
# screenshot the columns just right of the REC badge, on its row, hold none of the take line's
# red. Before, "REC  00:05:27:49  a_long_slate_name take 1" was right-aligned whatever the
# room and started at x 40, over the badge's own "REC  00:05:27:49" (red on red, unreadable);
# now it is shortened ("a_long_slate_name take 1") or left out where it does not fit.
# Usage: test_hud_corner.sh FACEPUPPET PLUGIN_DIR FACE RECORDING   (from the source root)
set -u
fp=$1 plugdir=$2 face=$3 rec=$4
. "$(dirname "$0")/live_shot.sh"
live_or_fail -q --plugin-dir "$plugdir" --mesh "$face" --input "replay:$rec" --size 320x240 \
    --take-dir "$tmp/takes" --slate a_long_slate_name \
    --script "key T; wait frames 5; shot $tmp/a.png; close"
shot_py "$tmp/a.png" <<'PY'
import sys

from pngread import read_png

w, h, bpp, rows = read_png(sys.argv[1])
px = lambda x, y: rows[y][bpp * x:bpp * x + 3]
near = lambda p, c, d: max(abs(p[k] - c[k]) for k in range(3)) <= d
badge = (230, 20, 20)      # REC's badge (hud.c: 0.9, 0.08, 0.08)
line_red = (242, 38, 31)   # the take line's red (takes.c: 0.95, 0.15, 0.12)
y_last = 8 + 15 - 1        # the badge's last row at scale 1: no text there
if not near(px(10, y_last), badge, 30):
    sys.exit("FAIL: no REC badge at the top left (%s)" % (px(10, y_last),))
x = 10
while x < w and near(px(x, y_last), badge, 30):
    x += 1
edge = x - 1
hits = [(cx, cy) for cy in range(8, y_last + 1) for cx in range(edge + 1, min(w, edge + 7))
        if near(px(cx, cy), line_red, 40)]
print("%dx%d: REC badge x 8..%d; %d red pixels of the take line in x %d..%d on its row"
      % (w, h, edge, len(hits), edge + 1, edge + 6))
if hits:
    sys.exit("FAIL: the take's line runs over the REC badge")
print("PASS")
PY
