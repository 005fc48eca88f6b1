#!/bin/sh
# A glove box at baud=1200 (a speed the cyberglove input takes), its bytes paced at that speed
# (paced_box.py: 22 sensors, timestamps on, the status byte: 30-byte records, 250 ms each on
# the line). Its records must be read (about 4 a second), with the rate warning, and no
# "glove stopped answering". Before: the default timeout (3 periods at rate=100, at least 250
# ms) ignored the line, and not one record was read: every probe ended in "glove stopped
# answering (no record for 250 ms)".
# Usage: test_slow_line.sh FACEPUPPET   (from the source root)
set -u
fp=$1
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-slow-line-XXXXXX")
trap 'kill $box 2>/dev/null; rm -rf "$tmp"' EXIT
python3 "$(dirname "$0")/paced_box.py" "$tmp/glove" 30 &
box=$!
for i in $(seq 100); do [ -e "$tmp/glove" ] && break; sleep 0.1; done
timeout 60 "$fp" monitor -d 5 "cyberglove:$tmp/glove,baud=1200" >"$tmp/out" 2>"$tmp/err"
rc=$?
grep -v joint_angles "$tmp/out"
cat "$tmp/err"
n=$(grep -c joint_angles "$tmp/out")
echo "$n records read in 5 s at 1200 baud"
[ $rc -eq 0 ] || { echo "FAIL: monitor exited $rc"; exit 1; }
[ "$n" -ge 8 ] || { echo "FAIL: $n records (about 4 a second expected)"; exit 1; }
if grep -q "stopped answering" "$tmp/out"; then echo "FAIL: said stopped answering"; exit 1; fi
grep -q "carries at most 4 records/s" "$tmp/out" || { echo "FAIL: no rate warning"; exit 1; }
echo PASS
