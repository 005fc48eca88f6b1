#!/bin/sh
# Out-of-tree plugin builds against an installed facepuppet, both ways, with warnings as
# errors (-Wall -Wextra -Werror): the installed headers alone must be enough, and the
# templates define none of the host's constants themselves. Args: BUILD_DIR DATA
set -eu
warn="-Wall -Wextra -Werror"
build=$(cd "$1" && pwd) data=$2 src=$(pwd)
tmp=$(mktemp -d /tmp/fp-sdk-XXXXXX)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null
test -f "$prefix/lib/pkgconfig/facepuppet.pc"
test -f "$prefix/lib/cmake/facepuppet/facepuppetConfig.cmake"
test -f "$prefix/share/doc/facepuppet/plugin-guide.md"
test -f "$prefix/share/facepuppet/templates/mapping/map_grab.c"
test -f "$prefix/include/facepuppet/errors.h"
# No local definitions of what plugin.h defines (FP_* macros or enumerators, e.g. a copy of
# FP_EPLUGIN_FAULT or FP_CONTROL_CAPACITY): a template takes them from the headers.
if grep -nE '^[[:space:]]*#[[:space:]]*define[[:space:]]+FP_|[^.[:alnum:]_]FP_[A-Z0-9_]+[[:space:]]*=[^=]' \
     "$prefix"/share/facepuppet/templates/*/*.c; then
  echo "a template defines a host constant itself (above)" >&2
  exit 1
fi
gen=""; command -v ninja >/dev/null && gen="-G Ninja"

# 1. CMake: the installed templates, copied as an author would copy them.
for t in mapping input; do
  cp -r "$prefix/share/facepuppet/templates/$t" "$tmp/$t"
  cmake -S "$tmp/$t" -B "$tmp/$t/build" $gen -DCMAKE_PREFIX_PATH="$prefix" \
        -DFP_DATA="$data" -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_FLAGS="$warn" \
        --no-warn-unused-cli >/dev/null
  cmake --build "$tmp/$t/build" >/dev/null
  ctest --test-dir "$tmp/$t/build" --output-on-failure
done
test -f "$tmp/mapping/build/map-grab.so"
test -f "$tmp/input/build/input-sine.so"

# 2. pkg-config: one compiler line each.
PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --exists facepuppet
mkdir "$tmp/pc"
cflags=$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags facepuppet)
libs=$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --libs facepuppet)
cc -std=c11 -O2 $warn -shared -fPIC $cflags -o "$tmp/pc/map-grab.so" "$tmp/mapping/map_grab.c" $libs
cc -std=c11 -O2 $warn -shared -fPIC -pthread $cflags -o "$tmp/pc/input-sine.so" \
   "$tmp/input/input_sine.c" $libs
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
echo "SDK: templates built with CMake and pkg-config ($warn) against $prefix; map-grab moved $moved vertices"

# 2b. C++: a mapping in C++ with facepuppet_add_plugin (project LANGUAGES CXX) and with g++
#     and pkg-config exports the entry, and only it (before: FP_PLUGIN_DECLARE_ENTRY gave a
#     const of internal linkage in C++, no symbol, "no-entry"; and the CMake function hid C
#     symbols only, so a C++ plugin exported all of its own).
if command -v c++ >/dev/null; then
  mkdir "$tmp/cxx"
  cp "$src/tests/plugin/fixture_cxx.cpp" "$tmp/cxx/map_cxx.cpp"
  printf '%s\n' 'cmake_minimum_required(VERSION 3.22)' 'project(map_cxx LANGUAGES CXX)' \
    'find_package(facepuppet 0.1 REQUIRED)' 'facepuppet_add_plugin(map-cxx map_cxx.cpp)' \
    >"$tmp/cxx/CMakeLists.txt"
  # a function of the plugin's own, not static: hidden too
  printf '%s\n' 'extern "C" int fp_test_cxx_helper(int x);' \
    'extern "C" int fp_test_cxx_helper(int x) { return x + 1; }' >>"$tmp/cxx/map_cxx.cpp"
  cmake -S "$tmp/cxx" -B "$tmp/cxx/build" $gen -DCMAKE_PREFIX_PATH="$prefix" \
        -DCMAKE_CXX_FLAGS="$warn" >/dev/null
  cmake --build "$tmp/cxx/build" >/dev/null
  c++ -std=c++17 -O2 $warn -shared -fPIC $cflags -o "$tmp/cxx/map-cxxpc.so" "$tmp/cxx/map_cxx.cpp" $libs
  for so in "$tmp/cxx/build/map-cxx.so" "$tmp/cxx/map-cxxpc.so"; do
    syms=$(nm -D --defined-only "$so" | awk '{print $3}' | grep -v '^_' || true)
    test "$syms" = "facepuppet_plugin_entry" || { echo "$so exports: $syms" >&2; exit 1; }
    "$prefix/bin/facepuppet" plugins check "$so" >"$tmp/cxx/check.out" 2>&1 ||
      { cat "$tmp/cxx/check.out" >&2; exit 1; }
  done
  echo "SDK: a C++ mapping built with CMake and pkg-config exports only its entry and passes plugins check"
fi

# 3. The installed plugin's folder, with CMake's install and pkg-config's plugindir: in this
#    build's layout the template's `cmake --install` into facepuppet's prefix puts map-grab.so
#    where facepuppet looks (found without --plugin-dir); and in Debian's multiarch layout
#    (LIBDIR lib/x86_64-linux-gnu: a second tree, configured only, its SDK and headers
#    installed) both name facepuppet's plugin folder and pkg-config's include folder holds
#    plugin.h (before: facepuppet_add_plugin installed into lib/facepuppet whatever the
#    layout, and the .pc file's prefix was its folder's ../.. , in multiarch LIBDIR itself).
cmake --install "$tmp/mapping/build" --prefix "$prefix" >/dev/null
test -f "$prefix/lib/facepuppet/map-grab.so"
"$prefix/bin/facepuppet" plugins | grep -q "^mapping grab .*org.example.map-grab"
ma=$tmp/multiarch
cmake -S "$src" -B "$ma/build" $gen -DCMAKE_INSTALL_LIBDIR=lib/x86_64-linux-gnu -DFP_BUILD_UI=OFF \
      -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --install "$ma/build/sdk" --prefix "$ma/prefix" >/dev/null
cmake --install "$ma/build/core/plugin" --prefix "$ma/prefix" >/dev/null # (the headers)
cp -r "$prefix/share/facepuppet/templates/mapping" "$ma/mapping"
cmake -S "$ma/mapping" -B "$ma/mapping/build" $gen -DCMAKE_PREFIX_PATH="$ma/prefix" \
      -DCMAKE_INSTALL_PREFIX="$ma/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$ma/mapping/build" >/dev/null
cmake --install "$ma/mapping/build" >/dev/null
test -f "$ma/prefix/lib/x86_64-linux-gnu/facepuppet/map-grab.so"
export PKG_CONFIG_PATH="$ma/prefix/lib/x86_64-linux-gnu/pkgconfig"
test "$(realpath "$(pkg-config --variable=plugindir facepuppet)")" = "$ma/prefix/lib/x86_64-linux-gnu/facepuppet"
test -f "$(pkg-config --variable=includedir facepuppet)/facepuppet/plugin.h"
cc -std=c11 -O2 $warn -shared -fPIC $(pkg-config --cflags facepuppet) -o "$ma/map-grab.so" \
   "$ma/mapping/map_grab.c" $(pkg-config --libs facepuppet)
echo "SDK: plugins installed into facepuppet's plugin folder (lib/ and lib/x86_64-linux-gnu/ layouts)"
