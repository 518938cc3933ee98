#!/usr/bin/env bash
# The main job on a real sample: installs what is missing, builds, fetches the sample meshes,
# converts the Stanford bunny into a .tom with its report and plots, shows what the file holds,
# and writes its 10% level.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
scripts/install-deps.sh
scripts/build.sh
scripts/fetch-samples.sh
mkdir -p out
echo
echo "== tombuild data/meshes/bunny00.off -o out/ --report --report-json out/reports"
build/tools/tombuild data/meshes/bunny00.off -o out/ -v --report --report-json out/reports
echo
echo "== scripts/plot-report.py out/reports/bunny00.json -o out/plots"
scripts/plot-report.py out/reports/bunny00.json -o out/plots
echo
echo "== tominfo out/bunny00.tom"
build/tools/tominfo out/bunny00.tom
echo
echo "== tomextract out/bunny00.tom --fraction 0.1 -o out/bunny00-10.obj"
build/tools/tomextract out/bunny00.tom --fraction 0.1 -o out/bunny00-10.obj
