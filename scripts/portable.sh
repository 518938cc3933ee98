#!/usr/bin/env bash
# Builds the portable part (runtime, builder, C API, libtcr) twice, warnings as errors, and runs
# its tests (the C API, format, extraction, libtcr's models and selectors) each time:
#   build-portable/clang    with clang++ on this machine;
#   build-portable/windows  cross-compiled for 64-bit Windows with mingw-w64, tests under wine64
#                           (a private wine prefix in build-portable/wine).
# The tests' real meshes are the samples converted by the Linux tombuild (build/tools, made by
# scripts/build.sh or scripts/test.sh) into build-portable/real.
# Usage: scripts/portable.sh [clang|windows]   (both by default)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="$root/build-portable"
tools="${TOM_TOOLS:-$root/build/tools}"
which="${1:-both}"
[ -x "$tools/tombuild" ] || { echo "portable.sh: $tools/tombuild is missing: run scripts/build.sh first" >&2; exit 1; }

# the real meshes the tests load (tests/support.cpp), as .tom files: one incremental batch, so a
# tombuild whose output changes (its options, its version) converts them again
real="$out/real"
mkdir -p "$real"
inputs=()
for f in meshes/bunny00.off meshes/fandisk.off meshes/cow.off meshes/elephant.off assimp/OBJ/WusonOBJ.obj assimp/OBJ/spider.obj \
         assimp/STL/Spider_binary.stl assimp/PLY/cube_binary.ply assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb; do
  [ -f "$root/data/$f" ] || { echo "portable.sh: data/$f is missing: run scripts/fetch-samples.sh" >&2; exit 1; }
  inputs+=("$root/data/$f")
done
"$tools/tombuild" "${inputs[@]}" -o "$real" -q

build_and_test() {  # build_and_test FOLDER CMAKE_OPTIONS...
  local dir="$out/$1"; shift
  echo "portable.sh: $(basename "$dir")"
  cmake -S "$root" -B "$dir" -DCMAKE_BUILD_TYPE=Release -DTOM_RUNTIME_ONLY=ON -DTOM_WERROR=ON -DTOM_REAL_TOM_DIR="$real" "$@" >/dev/null
  cmake --build "$dir" -j "$(nproc)" >/dev/null
  (cd "$dir" && ctest --output-on-failure -j "$(nproc)" | tail -n 3)
}

# The private wine prefix, made once, quietly. wineboot can return before the prefix is
# populated, or leave it half-made when interrupted: wait for its wineserver to exit, check that
# the prefix holds kernel32.dll, and make it again once when it does not.
make_wine_prefix() {
  local dll="$WINEPREFIX/drive_c/windows/system32/kernel32.dll" attempt
  for attempt in 1 2; do
    [ -f "$dll" ] && return 0
    rm -rf "$WINEPREFIX"
    /usr/lib/wine/wine64 wineboot --init >/dev/null 2>&1 || true
    /usr/lib/wine/wineserver64 -w || true
  done
  [ -f "$dll" ] || { echo "portable.sh: wineboot did not make a usable prefix in $WINEPREFIX (no kernel32.dll)" >&2; exit 1; }
}

if [ "$which" = both ] || [ "$which" = clang ]; then
  build_and_test clang -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
fi
if [ "$which" = both ] || [ "$which" = windows ]; then
  [ -x /usr/lib/wine/wine64 ] && command -v x86_64-w64-mingw32-g++-posix >/dev/null || {
    echo "portable.sh: mingw-w64 or wine64 is missing: run scripts/install-deps.sh" >&2; exit 1; }
  export WINEPREFIX="$out/wine" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml="
  make_wine_prefix
  # one wineserver for the whole run: left alone it exits whenever no wine process is alive, and
  # a test that starts as it goes fails at once, with no output of its own but wine's "wine
  # client error:0: recvmsg: Connection reset by peer" (seen under ctest -j 2, one test in about
  # three runs of the suite). Its services start with the first wine process and live as long
  # as it does, keeping that process's output open: a first test would hold ctest until its
  # timeout, so wineboot starts them here, its output nowhere. (The suite also runs in half the
  # time: no server start per test.)
  /usr/lib/wine/wineserver64 -p
  trap '/usr/lib/wine/wineserver64 -k 2>/dev/null || true' EXIT
  /usr/lib/wine/wine64 wineboot </dev/null >/dev/null 2>&1 || true
  build_and_test windows -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake"
fi
