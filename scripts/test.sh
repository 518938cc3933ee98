#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds, fetches the sample meshes, runs ctest,
# then builds the portable part with clang++ and for Windows and runs its tests (under wine).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
scripts/install-deps.sh
scripts/build.sh
scripts/fetch-samples.sh
ctest --test-dir build --output-on-failure -j "$(nproc)" "$@"
scripts/portable.sh
