#!/bin/sh
# The camera keeps its framing when live's window is resized (run under xvfb-run by ctest;
# ui/viewer/viewer.c keep_framing). live shows the ICT face in a 640x480 window without its
# HUD (Tab), then the script resizes it to 240x480 (narrower than the face was framed for),
# 960x360 (wide) and back to 640x480, with a screenshot at each. In each PNG the face's
# bounding box (the pixels away from the clear colour) must lie inside the window with a margin
# (the face not cut off) and fill a similar share of the window's limiting side as when framed
# (0.6..1.25 times the first shot's). Before: the camera kept its distance, so at 240x480 the
# face ran off both sides (box touching the edges) until key F reframed it.
# Usage: test_resize_framing.sh FACEPUPPET PLUGIN_DIR FACE   (from the source root)
set -u
fp=$1 plugdir=$2 face=$3
. "$(dirname "$0")/live_shot.sh"
live_or_fail -q --plugin-dir "$plugdir" --mesh "$face" --size 640x480 --script \
    "key Tab; wait frames 5; shot $tmp/a.png; size 240x480; wait frames 15; shot $tmp/b.png; \
size 960x360; wait frames 15; shot $tmp/c.png; size 640x480; wait frames 15; shot $tmp/d.png; close" \
   
shot_py "$tmp" <<'PY'
import sys

from pngread import read_png

def face_box(path):
    w, h, bpp, rows = read_png(path)
    bg = rows[0][0:3]  # the corner: the clear colour
    xs, ys = [], []
    for y in range(h):
        r = rows[y]
        for x in range(w):
            if max(abs(r[bpp * x + k] - bg[k]) for k in range(3)) > 12:
                xs.append(x)
                ys.append(y)
    if not xs:
        sys.exit("FAIL: %s: no face drawn" % path)
    return w, h, min(xs), min(ys), max(xs), max(ys)

def share(w, h, x0, y0, x1, y1):
    # the share of the side that limits the face's size: its box against the window's
    return max((x1 - x0 + 1) / w, (y1 - y0 + 1) / h)

first = None
for name in "abcd":
    w, h, x0, y0, x1, y1 = face_box("%s/%s.png" % (sys.argv[1], name))
    s = share(w, h, x0, y0, x1, y1)
    print("%s.png %dx%d: face box x %d..%d y %d..%d, share %.3f" % (name, w, h, x0, x1, y0, y1, s))
    if x0 < 2 or y0 < 2 or x1 > w - 3 or y1 > h - 3:
        sys.exit("FAIL: %s.png (%dx%d): the face is cut off by the window's edge" % (name, w, h))
    first = first or s
    if not 0.6 * first <= s <= 1.25 * first:
        sys.exit("FAIL: %s.png (%dx%d): the face fills %.3f of the window, %.3f when framed"
                 % (name, w, h, s, first))
print("PASS")
PY
