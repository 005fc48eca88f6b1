#!/bin/sh
# The viewer's opening screen (run under xvfb-run with -fbdir by ctest): while a session opens,
# the window shows the step alone. The fixture input's create takes 4 s (open_ms=4000), so the
# step "loading the mapping and 1 input" stays up that long; Xvfb's screen, a file in XWD format
# (-fbdir), is read meanwhile: text at the window's top left, the background everywhere below
# it (no face yet). Then the session opens and live ends after 3 frames with the face drawn.
# Usage: test_opening_screen.sh FACEPUPPET FIXTURE_DIR FBDIR   (from the source root)
set -u
fp=$1 fx=$2 fb=$3
py=/usr/bin/python3
[ -x "$py" ] || py=python3
tmp=$(mktemp -d)
"$fp" live --plugin-dir "$fx" --input "fixture:,open_ms=4000" --size 640x480 --frames 3 \
    >"$tmp/out" 2>"$tmp/err" &
pid=$!
trap 'kill $pid 2>/dev/null; rm -rf "$tmp"' EXIT
"$py" - "$fb/Xvfb_screen0" "$pid" <<'PY'
import os, struct, sys, time

def screen(path):
    d = open(path, "rb").read()
    f = struct.unpack(">25I", d[:100])
    w, h, bpp, bpl, ncolors = f[4], f[5], f[11], f[12], f[19]
    assert bpp == 32, f"{bpp} bits a pixel"
    off = f[0] + 12 * ncolors
    return lambda x, y: tuple(d[off + y * bpl + 4 * x + 2 - k] for k in range(3))  # r, g, b

bg = (28, 31, 38)  # the clear colour (0.11, 0.12, 0.15)
near_bg = lambda p: all(abs(a - b) <= 3 for a, b in zip(p, bg))
deadline = time.time() + 60
while time.time() < deadline:
    try:
        os.kill(int(sys.argv[2]), 0)
    except OSError:
        sys.exit("FAIL: live ended before its opening screen was seen")
    try:
        px = screen(sys.argv[1])
        text = sum(1 for y in range(0, 24) for x in range(0, 600) if min(px(x, y)) > 200)
        below = sum(1 for y in range(40, 480, 4) for x in range(0, 640, 4) if not near_bg(px(x, y)))
    except (OSError, AssertionError, struct.error, IndexError):
        time.sleep(0.1)
        continue
    if text > 50 and below == 0:
        print(f"opening screen: {text} text pixels at the top left, the background below")
        sys.exit(0)
    time.sleep(0.1)
sys.exit("FAIL: no opening screen in 60 s")
PY
rc=$?
[ $rc = 0 ] || { cat "$tmp/err"; exit 1; }
wait $pid || { echo "FAIL: live exited $?"; cat "$tmp/err"; exit 1; }
grep -q "^frames 3" "$tmp/out" || { echo "FAIL: no report of 3 frames"; cat "$tmp/out" "$tmp/err"; exit 1; }
echo "ok: live opened and ran 3 frames"
