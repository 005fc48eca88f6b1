# Sourced by live's screenshot tests (test_hud_room.sh, test_hud_corner.sh, test_hud_bottom.sh,
# test_resize_framing.sh), after they set fp: $tmp, a folder removed at exit; live_or_fail
# ARGS... runs `$fp live ARGS` with its output in $tmp/out and $tmp/err, and on an exit other
# than 0 prints $tmp/err and exits 1; shot_py ARGS... runs the python script on its standard
# input with tests/support (pngread.py) on the path.
# SPDX-License-Identifier: GPL-3.0-or-later
py=/usr/bin/python3
[ -x "$py" ] || py=python3
support="$(dirname "$0")/../support"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
live_or_fail() {
    "$fp" live "$@" >"$tmp/out" 2>"$tmp/err"
    rc=$?
    if [ $rc -ne 0 ]; then
        cat "$tmp/err"
        echo "FAIL: live exited $rc"
        exit 1
    fi
}
shot_py() { PYTHONPATH="$support" "$py" - "$@"; }
