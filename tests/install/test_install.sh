#!/bin/sh
# After `cmake --install`, the installed facepuppet finds its installed plugins relative
# to its own location, and runs a short session. Args: BUILD_DIR SHARED_DATA
set -eu
build=$1 data=$2
prefix=$(mktemp -d /tmp/fp-install-XXXXXX)
trap 'rm -rf "$prefix"' EXIT
cmake --install "$build" --prefix "$prefix" >/dev/null
test -x "$prefix/bin/facepuppet"
test -f "$prefix/include/facepuppet/plugin.h"
test -x "$prefix/share/facepuppet/plot_fig3.py" # bench --plot finds it there
cd "$prefix"
FACEPUPPET_PLUGIN_PATH= "$prefix/bin/facepuppet" run -q \
  --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" \
  --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,speed=8" --out out.obj
test -s out.obj
# and the plugins it used are the installed ones: with them gone, it must fail with 78.
mv "$prefix/lib" "$prefix/lib.moved"
set +e
"$prefix/bin/facepuppet" run -q --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" \
  --input "replay:$data/hands/leap-motion/grab_joints_mm.csv" --out out2.obj 2>/dev/null
rc=$?
set -e
test "$rc" = 78
mv "$prefix/lib.moved" "$prefix/lib"
# The shared data: an installed binary does not read the build tree's ../shared/data (before:
# the demo ran from the build tree's data, and broke when that tree went). FP_SHARED_DATA,
# else PREFIX/share/facepuppet/data; neither: "no shared data folder", exit 66.
set +e
env -u FP_SHARED_DATA "$prefix/bin/facepuppet" run -q --duration 0.1 --out demo.obj 2>nodata.err
rc=$?
set -e
test "$rc" = 66 || { cat nodata.err; echo "installed demo without data: exit $rc, want 66"; exit 1; }
grep -q "no shared data folder for faces/ict-facekit/generic_neutral_mesh.obj: set FP_SHARED_DATA" nodata.err
test ! -e demo.obj
FP_SHARED_DATA="$data" "$prefix/bin/facepuppet" run -q --duration 0.1 --out demo1.obj
test -s demo1.obj
ln -s "$(cd "$data" && pwd)" "$prefix/share/facepuppet/data"
env -u FP_SHARED_DATA "$prefix/bin/facepuppet" run -q --duration 0.1 --out demo2.obj
test -s demo2.obj
echo "installed facepuppet ran from $prefix and found its plugins there"
