#!/bin/sh
# Hot reload in `facepuppet live` (run under xvfb-run by ctest): the mapping's .so is fixture
# build A in a private plugin folder; replaced by build B (never engages, version "B"), the
# next frames use B; replaced by a broken file, B stays and the message says why. With -q:
# both lines print all the same (before: -q kept the failed reload's error from stderr); the
# failure's cause is said once, without a doubled "mapping 'hot': " (an isolated load's).
# Usage: test_hot_reload.sh FACEPUPPET FIXTURE_DIR   (from the source root)
set -u
fp=$1 fx=$2
data=${FP_SHARED_DATA:-../shared/data}
rec=$data/hands/leap-motion/three-claps_joints_mm.csv
tmp=$(mktemp -d)
chmod 700 "$tmp"
mkdir "$tmp/plugins"
cp "$fx/map-fixture.so" "$tmp/plugins/map-hot.so"
chmod 755 "$tmp/plugins"; chmod 644 "$tmp/plugins/map-hot.so"
"$fp" live -q --plugin-dir "$tmp/plugins" --mapping hot --input "replay:$rec,loop=1" --size 160x120 \
    --frames 100000 --script 'wait hands; wait frames 5; print mapping; wait reload; wait frames 5;
    print mapping; wait reload; wait frames 3; print mapping; close' >"$tmp/out" 2>"$tmp/err" &
pid=$!
trap 'kill $pid 2>/dev/null; rm -rf "$tmp"' EXIT
# wait_for N PATTERN: until line N of the output matches (30 s at most)
wait_for() {
    i=0
    while ! sed -n "$1p" "$tmp/out" | grep -Eq "$2"; do
        i=$((i + 1))
        if [ $i -gt 300 ] || ! kill -0 $pid 2>/dev/null; then
            echo "FAIL: no line $1 matching '$2'"; cat "$tmp/out" "$tmp/err"; exit 1
        fi
        sleep 0.1
    done
    echo "ok: $(sed -n "$1p" "$tmp/out")"
}
wait_for 1 '^mapping hot id org.facepuppet.test.map-fixture version A .*active 1 count [1-9]'
cp "$fx/map-fixture-b.so" "$tmp/plugins/.map-hot.new" && mv "$tmp/plugins/.map-hot.new" "$tmp/plugins/map-hot.so"
wait_for 2 '^mapping hot id org.facepuppet.test.map-fixture version B .*active 0 count 0 reloads 1'
printf 'not a shared object\n' >"$tmp/plugins/.map-hot.new" && mv "$tmp/plugins/.map-hot.new" "$tmp/plugins/map-hot.so"
wait_for 3 '^mapping hot id org.facepuppet.test.map-fixture version B .*reloads 1$'
wait $pid
rc=$?
trap 'rm -rf "$tmp"' EXIT
grep -E "mapping 'hot' reloaded from .*map-hot.so \(org.facepuppet.test.map-fixture B\)" "$tmp/err" ||
    { echo "FAIL: no reload line"; cat "$tmp/err"; exit 1; }
grep -E "mapping 'hot': reload of .*map-hot.so failed: .*(invalid ELF header|file too short).*keeping the old one" "$tmp/err" ||
    { echo "FAIL: no failed-reload line naming the cause"; cat "$tmp/err"; exit 1; }
grep -E "reload of .* failed: mapping 'hot'" "$tmp/err" && { echo "FAIL: the name said twice"; exit 1; }
[ $rc = 0 ] || { echo "FAIL: live exited $rc"; cat "$tmp/err"; exit 1; }
echo "hot reload: ok"
