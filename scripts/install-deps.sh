#!/usr/bin/env bash
# Installs every dependency of the project from Debian's packages (bookworm). Run as root.
# Does nothing when everything is already installed.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libopenmesh-dev                      # OBJ/PLY/OFF/STL import
  libtinygltf-dev nlohmann-json3-dev   # glTF import (tinygltf needs nlohmann json)
  libdraco-dev                         # KHR_draco_mesh_compression
  libcli11-dev                         # command lines
  catch2                               # tests (v2)
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev libeigen3-dev   # Metro-style distances (AABB trees)
  libmeshoptimizer-dev                 # benchmark reference only
  libosmesa6-dev libegl-dev libgl-dev libstb-dev  # headless rendering (Mesa), PNG screenshots
  python3 python3-matplotlib python3-jsonschema   # plots; report schema check in the tests
  python3-skimage                      # SSIM and PSNR of the walkthrough's frames against full detail (tcrwalk --quality-every)
  valgrind                             # instruction counts in benchmarks
  clang libclang-rt-14-dev             # libFuzzer and the sanitizers' runtime (scripts/fuzz.sh, CI's sanitizer run)
  python3-dev python3-numpy python3-pybind11 python3-pytest   # the Python package (python/) and its tests
  g++-mingw-w64-x86-64-posix wine64    # the Windows build of the runtime and its tests under wine (scripts/portable.sh)
  libcgal-demo assimp-testmodels       # sample meshes (copied into data/ by scripts/fetch-samples.sh)
  assimp-utils                         # converts the samples' Collada and FBX models to glTF (scripts/fetch-samples.sh)
  libxxhash-dev                        # tombuild's digests of inputs (incremental conversion)
  slurm-wlm munge                      # the Slurm job-array test starts a one-node cluster (tests/cli/slurm_test.sh)
  parallel                             # GNU parallel: the README's shard recipe, run by tests/cli/batch_test.sh
  emscripten chromium                  # the browser runtime (scripts/build-web.sh) and its test in headless chromium
)

# node and npm run Khronos' glTF validator and gltfpack in the tests (from the npm registry, below)
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
root="$(cd "$(dirname "$0")/.." && pwd)"
install_validator() {
  # from the npm registry into the git-ignored .tools/: Khronos' glTF validator (checks
  # tomextract's .glb output), gltfpack 0.18, the version of Debian's meshoptimizer decoders
  # (writes the KHR_mesh_quantization / EXT_meshopt_compression inputs the tests decode), and
  # the current gltfpack (1.3, as gltfpack-current), the yardstick of scripts/bench.sh; three.js
  # and meshoptimizer's JavaScript decoder (1.3, gltfpack's) for the browser runtime and viewer
  local m="$root/.tools/node_modules"
  if [ ! -f "$m/gltf-validator/package.json" ] || [ ! -f "$m/gltfpack/package.json" ] || [ ! -f "$m/gltfpack-current/package.json" ] ||
     [ ! -f "$m/three/package.json" ] || [ ! -f "$m/meshoptimizer/package.json" ]; then
    mkdir -p "$root/.tools"
    npm install --silent --no-audit --no-fund --save-exact --prefix "$root/.tools" gltf-validator@2.0.0-dev.3.10 gltfpack@0.18.0 \
      gltfpack-current@npm:gltfpack@1.3.0 three@0.187.0 meshoptimizer@1.3.0 >/dev/null
    echo "install-deps: gltf-validator, gltfpack 0.18 and 1.3, three 0.187 and meshoptimizer 1.3 installed in .tools/"
  fi
}
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  install_validator
  exit 0
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages: ${missing[*]}" >&2
  echo "install-deps: run as root (or: sudo $0)" >&2
  exit 1
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
install_validator
echo "install-deps: done"
