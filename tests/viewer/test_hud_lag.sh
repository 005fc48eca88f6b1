#!/bin/sh
# The HUD's lag readout (under Xvfb): beside the frame time, the median over the last second
# of the event-to-frame latency, in frames and ms (ui/viewer/measure.c fp_vmeasure_lag, the
# function the exit line's latency comes from too); "-" while no hand sample was shown in the
# last second. `print hud` gives the readout the HUD draws. Before, the HUD had no lag: the
# performer read it only in the exit line.
#   - at the first frame, no hand yet: "lag -"
#   - 1.5 s into the replay: "lag X frames (Y ms)", Y within a frame of the exit line's
#     median: at most the exit line's frame time (its median, the whole run's) from its
#     latency. Compared in ms, not in frames: the HUD's frames are over the last second's
#     frame time, the exit line's over the whole run's, which the frames after the replay's
#     end make shorter (CI: 7.7 ms against 6.34 ms, 1.6 frames against 2.8)
#   - 2 s after the replay's end (no sample since): "lag -" again
# Usage: test_hud_lag.sh FACEPUPPET PLUGIN_DIR MESH RECORDING
set -u
fp=$1 plugins=$2 mesh=$3 rec=$4
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-hud-lag-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
"$fp" live -q --plugin-dir "$plugins" --size 320x240 --mesh "$mesh" --rig none \
    --input "replay:$rec" \
    --script "print hud; wait hands; wait seconds 1.5; print hud; wait end; wait seconds 2; print hud; close" \
    >"$tmp/out.txt" 2>"$tmp/err.txt"
rc=$?
cat "$tmp/out.txt"
[ $rc -eq 0 ] || { cat "$tmp/err.txt"; echo "FAIL: live exited $rc"; exit 1; }
fail=0
hud() { grep '^hud ' "$tmp/out.txt" | sed -n "${1}p"; }
[ "$(grep -c '^hud ' "$tmp/out.txt")" -eq 3 ] || { echo "FAIL: not 3 hud lines"; exit 1; }
hud 1 | grep -q ' lag - hands ' || { echo "FAIL: no 'lag -' before any hand"; fail=1; }
hud 3 | grep -q ' lag - hands ' || { echo "FAIL: no 'lag -' 2 s after the last sample"; fail=1; }
mid=$(hud 2 | sed -n 's/.* lag \(-\{0,1\}[0-9.]*\) frames (\(-\{0,1\}[0-9.]*\) ms) hands .*/\1 \2/p')
[ -n "$mid" ] || { echo "FAIL: no 'lag X frames (Y ms)' while the hands move"; exit 1; }
exit_line=$(grep '^frames ' "$tmp/out.txt")
ex=$(printf '%s\n' "$exit_line" |
     sed -n 's/.*frame time median \([0-9.]*\) ms.*latency median \(-\{0,1\}[0-9.]*\) ms (\(-\{0,1\}[0-9.]*\) frames).*/\1 \2 \3/p')
[ -n "$ex" ] || { echo "FAIL: no frame time and latency in frames in the exit line"; exit 1; }
if awk -v mid="$mid" -v ex="$ex" 'BEGIN {
        split(mid, h, " "); split(ex, e, " ")
        printf "HUD lag %s frames (%s ms); exit line %s frames (%s ms, frame time %s ms)\n", h[1], h[2], e[3], e[2], e[1]
        d = h[2] - e[2]; if (d < 0) d = -d
        exit !(d <= e[1] && h[1] >= 0 && h[2] >= 0) }'; then
    echo "the HUD's lag is within a frame of the exit line's"
else
    echo "FAIL: the HUD's lag is not within a frame of the exit line's (or negative)"
    fail=1
fi
[ $fail -eq 0 ] && echo PASS
exit $fail
