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
echo "installed facepuppet ran from $prefix and found its plugins there"
