#!/usr/bin/env bash
# The whole test suite: installs what is missing, builds, fetches the sample meshes, runs ctest.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
scripts/install-deps.sh
scripts/build.sh
scripts/fetch-samples.sh
ctest --test-dir build --output-on-failure -j "$(nproc)" "$@"
