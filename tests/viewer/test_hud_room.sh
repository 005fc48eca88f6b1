#!/bin/sh
# The HUD's messages stop above the window's bottom (ui/viewer/hud.c fp_hud_fit, overdub.c
# fp_voverdub_bottom_top): live shows the ICT face in a 640x480 window (hands hidden, H), six
# dropped mesh files that are not there each leave a long "cannot load ..." answer (five
# wrapped lines each), and a screenshot is taken. The band of the "? keys" line at the bottom
# (its last 15 rows, right of the "? keys" text) must hold the background alone. Before, the
# stack ran 470 px down from y 110, past the window's bottom and over "? keys"; the same held
# with the take strip, whose line and strip the messages overran (the take's confirmation,
# drawn last, lay under the strip).
# Usage: test_hud_room.sh FACEPUPPET PLUGIN_DIR FACE   (from the source root)
set -u
fp=$1 plugdir=$2 face=$3
. "$(dirname "$0")/live_shot.sh"
long=""
for i in 1 2 3 4 5 6 7 8 9 10 11 12 13 14; do long="${long}a_folder_that_is_not_there_"; done
drops=""
for i in 1 2 3 4 5 6; do drops="$drops drop $tmp/none$i/$long/face$i.obj;"; done
live_or_fail -q --plugin-dir "$plugdir" --mesh "$face" --size 640x480 --script \
    "key H; wait frames 2; $drops wait frames 2; shot $tmp/a.png; close"
n=$(grep -c 'cannot load' "$tmp/err")
if [ "$n" -ne 6 ]; then
    cat "$tmp/err"
    echo "FAIL: $n 'cannot load' answers, 6 expected"
    exit 1
fi
shot_py "$tmp/a.png" <<'PY'
import sys

from pngread import read_png

w, h, bpp, rows = read_png(sys.argv[1])
bg = rows[h - 1][bpp * (w - 1):bpp * (w - 1) + 3]  # bottom right: never text (wrapped to w - 16)
hits = 0
for y in range(h - 15, h):
    r = rows[y]
    for x in range(70, w - 8):  # right of "? keys" (x 8..44 at scale 1)
        if max(abs(r[bpp * x + k] - bg[k]) for k in range(3)) > 24:
            hits += 1
print("%dx%d: %d pixels off the background in the bottom band (rows %d..%d, x 70..%d)"
      % (w, h, hits, h - 15, h - 1, w - 9))
if hits:
    sys.exit("FAIL: the HUD's messages run into the bottom of the window, over '? keys'")
print("PASS")
PY
