#!/usr/bin/env bash
# Builds the browser runtime and the viewer into a static site (build-web/site/):
#   - libtom's runtime (reader, stream decoder, extraction) and its WebAssembly face
#     (libtom/web/src/tom_web.cpp) compiled with Debian's emscripten into tom_wasm.mjs + .wasm;
#   - the ES module tom.mjs and the three.js loader TOMLoader.mjs (libtom/web/) with their
#     TypeScript declarations;
#   - the viewer (samples/web/) and, from npm (pinned by scripts/install-deps.sh), three.js and
#     meshoptimizer's decoder under vendor/, named by the page's import map.
# Rebuilds only what changed. Serve the folder with any static server (scripts/serve-web.sh).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${TOM_WEB_BUILD:-$root/build-web}"
site="$out/site"
modules="$root/.tools/node_modules"
command -v em++ >/dev/null || { echo "build-web: em++ not found; run scripts/install-deps.sh (Debian's emscripten)" >&2; exit 1; }
[ -f "$modules/three/package.json" ] && [ -f "$modules/meshoptimizer/package.json" ] ||
  { echo "build-web: three or meshoptimizer missing in .tools/; run scripts/install-deps.sh" >&2; exit 1; }
# Debian's emscripten finds its node modules (acorn) where Debian's node looks; another node
# (nodesource's) needs to be told
export NODE_PATH="${NODE_PATH:+$NODE_PATH:}/usr/share/nodejs"
mkdir -p "$out/obj" "$site/vendor/three"

flags=(-std=c++17 -O2 -fwasm-exceptions -DNDEBUG -I"$root/libtom/runtime/include" -I"$root/libtom/internal")
sources=("$root"/libtom/runtime/src/*.cpp "$root/libtom/web/src/tom_web.cpp")
objects=()
pids=()
for src in "${sources[@]}"; do
  obj="$out/obj/$(basename "$src" .cpp).o"
  objects+=("$obj")
  # an object is current when newer than its source and every header it may include
  if [ -f "$obj" ] && [ -z "$(find "$src" "$root/libtom/runtime/include" "$root/libtom/internal" -newer "$obj" -print -quit)" ]; then continue; fi
  em++ "${flags[@]}" -c "$src" -o "$obj" &
  pids+=($!)
  # at most two compilers at a time
  if [ ${#pids[@]} -ge 2 ]; then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi
done
for p in "${pids[@]}"; do wait "$p"; done

if [ ! -f "$site/tom_wasm.wasm" ] || [ -n "$(find "${objects[@]}" -newer "$site/tom_wasm.wasm" -print -quit)" ]; then
  em++ -O2 -fwasm-exceptions "${objects[@]}" -o "$site/tom_wasm.mjs" \
    -sMODULARIZE=1 -sEXPORT_ES6=1 -sEXPORT_NAME=createTomWasm -sENVIRONMENT=web,worker \
    -sALLOW_MEMORY_GROWTH=1 -sEXPORTED_FUNCTIONS=_malloc,_free -sEXPORTED_RUNTIME_METHODS=UTF8ToString,stringToUTF8,lengthBytesUTF8
  echo "build-web: $site/tom_wasm.wasm ($(stat -c %s "$site/tom_wasm.wasm") bytes)"
fi

# the modules, the viewer and the vendored-at-build npm files (copies into the git-ignored site)
cp -u "$root"/libtom/web/*.mjs "$root"/libtom/web/*.d.ts "$root"/samples/web/*.html "$root"/samples/web/viewer.mjs "$root"/samples/web/bench.mjs "$root"/samples/web/*.css "$site/"
cp -u "$modules"/three/build/three.module.js "$modules"/three/build/three.core.js "$site/vendor/three/"
cp -u "$modules"/three/examples/jsm/controls/OrbitControls.js "$site/vendor/three/"
cp -u "$modules"/three/LICENSE "$site/vendor/three/LICENSE"
cp -u "$modules"/meshoptimizer/meshopt_decoder.mjs "$site/vendor/meshopt_decoder.mjs"
cp -u "$modules"/meshoptimizer/meshopt_encoder.js "$site/vendor/meshopt_encoder.js"
cp -u "$modules"/meshoptimizer/LICENSE.md "$site/vendor/meshoptimizer-LICENSE.md"
