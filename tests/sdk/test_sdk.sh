#!/bin/sh
# Out-of-tree plugin builds against an installed facepuppet, both ways. Args: BUILD_DIR DATA
set -eu
build=$(cd "$1" && pwd) data=$2 src=$(pwd)
tmp=$(mktemp -d /tmp/fp-sdk-XXXXXX)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null
test -f "$prefix/lib/pkgconfig/facepuppet.pc"
test -f "$prefix/lib/cmake/facepuppet/facepuppetConfig.cmake"
test -f "$prefix/share/doc/facepuppet/plugin-guide.md"
test -f "$prefix/share/facepuppet/templates/mapping/map_grab.c"
gen=""; command -v ninja >/dev/null && gen="-G Ninja"

# 1. CMake: the installed templates, copied as an author would copy them.
for t in mapping input; do
  cp -r "$prefix/share/facepuppet/templates/$t" "$tmp/$t"
  cmake -S "$tmp/$t" -B "$tmp/$t/build" $gen -DCMAKE_PREFIX_PATH="$prefix" \
        -DFP_DATA="$data" -DCMAKE_BUILD_TYPE=Release --no-warn-unused-cli >/dev/null
  cmake --build "$tmp/$t/build" >/dev/null
  ctest --test-dir "$tmp/$t/build" --output-on-failure
done
test -f "$tmp/mapping/build/map-grab.so"
test -f "$tmp/input/build/input-sine.so"

# 2. pkg-config: one compiler line.
PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --exists facepuppet
mkdir "$tmp/pc"
cc -std=c11 -O2 -shared -fPIC $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags facepuppet) \
   -o "$tmp/pc/map-grab.so" "$tmp/mapping/map_grab.c" \
   $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --libs facepuppet)
cd "$tmp"
out=$("$prefix/bin/facepuppet" run --plugin-dir "$tmp/pc" --mapping grab \
      --mesh "$data/faces/mediapipe-canonical/canonical_face_model.obj" \
      --input "replay:$data/hands/leap-motion/grab_joints_mm.csv,speed=2" --out "$tmp/pc.obj" 2>&1)
echo "$out" | tail -1
moved=$(echo "$out" | sed -n 's/.*vertices moved \([0-9]*\) of.*/\1/p' | tail -1)
test -n "$moved" && test "$moved" -gt 0
# Only the entry symbol is exported.
syms=$(nm -D --defined-only "$tmp/pc/map-grab.so" | awk '{print $3}' | grep -v '^_' || true)
test "$syms" = "facepuppet_plugin_entry"
echo "SDK: templates built with CMake and pkg-config against $prefix; map-grab moved $moved vertices"
