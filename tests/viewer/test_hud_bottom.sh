#!/bin/sh
# The bottom of live's window in a narrow, short one (480x600, the HUD's scale 2): the take
# strip's line is shortened to the strip's width (ui/viewer/takes.c fit_hints) and the rig's
# legend (G) stops above it (ui/viewer/overlay.c fp_overlay_rig_legend's room). live records
# a take of the HandSplay recording through onehand, stops it, shows the rig (G), and in the
# screenshot, the face zoomed out (camera 0 0 0.5) to keep clear of the left margin, (a) the
# last 20 columns on the strip line's rows hold none of its light grey text (its whole line
# is 52 characters, 624 px: shortened, "take 1: V review   P play" ends at x 308), (b) the
# window's bottom from the strip line's band down (but the strip), at x 8..99, holds none of
# the legend's colours (skull blue, jaw red, soft green, landmarks white, hinge cyan).
# Before: "take 1: V review   P play   mouse on the strip: scrub" ran off the window's right
# edge, cut ("... mouse on the"), and the legend's "soft: jaw weight" and "landmarks" rows
# were drawn over it and on under the strip, over "? keys".
# Usage: test_hud_bottom.sh FACEPUPPET PLUGIN_DIR FACE RECORDING   (from the source root)
set -u
fp=$1 plugdir=$2 face=$3 rec=$4
. "$(dirname "$0")/live_shot.sh"
live_or_fail -q --plugin-dir "$plugdir" --mesh "$face" --mapping onehand --input "replay:$rec" \
    --size 480x600 --take-dir "$tmp/takes" \
    --script "key T; wait frames 8; key T; wait frames 2; key G; camera 0 0 0.5; wait frames 2; shot $tmp/a.png; close" \
   
shot_py "$tmp/a.png" <<'PY'
import sys

from pngread import read_png

w, h, bpp, rows = read_png(sys.argv[1])
px = lambda x, y: rows[y][bpp * x:bpp * x + 3]
near = lambda p, c, d: max(abs(p[k] - c[k]) for k in range(3)) <= d
scale = 2 if h >= 600 else 1
strip_y = h - 18 * scale - 28 * scale        # takes.c fp_vtakes_strip_rect
line_y0, line_y1 = strip_y - 14 * scale, strip_y - 2 * scale  # the strip's line of text
dim = (204, 217, 230)                         # its colour (0.8, 0.85, 0.9)
edge = [(x, y) for y in range(line_y0, line_y1) for x in range(w - 20, w) if near(px(x, y), dim, 30)]
colours = [(77, 115, 255), (255, 77, 38), (77, 204, 77), (255, 255, 255), (0, 230, 255)]  # overlay.c
strip = range(strip_y, strip_y + 18 * scale)  # the strip itself (its "T1" near white)
legend = [(x, y) for y in range(line_y0 - 10 * scale, h) if y not in strip for x in range(8, 100)
          if any(near(px(x, y), c, 12 if c == (255, 255, 255) else 40) for c in colours)]
print("%dx%d: strip line rows %d..%d: %d of its pixels in the last 20 columns; %d legend pixels "
      "at x 8..99 from row %d" % (w, h, line_y0, line_y1 - 1, len(edge), len(legend),
                                                  line_y0 - 10 * scale))
if edge:
    sys.exit("FAIL: the take strip's line runs off the window's right edge")
if legend:
    sys.exit("FAIL: the rig's legend is drawn over the take strip's line")
print("PASS")
PY
