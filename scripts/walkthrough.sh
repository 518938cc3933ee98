#!/usr/bin/env bash
# The walkthrough in one command: installs what is missing, builds, fetches the sample meshes,
# converts them with tombuild (the spider textured: its images are copied beside its .tom, where
# tcrwalk looks for them), lays out a scene of 300 instances and a far ring of 200 (where
# imposters pay), calibrates the cost model on the headless renderer, renders the path under every selector, and writes the table, the CSV,
# the plots, the screenshots, the image against full detail (SSIM, PSNR every 10th frame) and
# the renderer's noise test to out/walk/.
# usage: bash scripts/walkthrough.sh [BUDGET_MS=40] [FRAMES=300]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
budget="${1:-40}"; frames="${2:-300}"
scripts/install-deps.sh
scripts/build.sh
scripts/fetch-samples.sh
out=out/walk
mkdir -p "$out"
build/tools/tombuild data/meshes/bunny00.off data/meshes/fandisk.off data/meshes/cow.off data/meshes/elephant.off \
  data/meshes/mushroom.off data/assimp/OBJ/WusonOBJ.obj data/assimp/OBJ/spider.obj -o "$out/meshes" -j 2 -q
cp data/assimp/OBJ/*.jpg "$out/meshes/"
build/samples/walkthrough/tcrwalk --make-scene "$out/scene.txt" --meshes "$out"/meshes/*.tom --instances 300 --far-instances 200 --seed 1
build/samples/walkthrough/tcrwalk --scene "$out/scene.txt" --calibrate "$out/calibration.txt"
build/samples/walkthrough/tcrwalk --scene "$out/scene.txt" --calibration "$out/calibration.txt" --budget-ms "$budget" \
  --frames "$frames" --selector all --out "$out/run" --quality-every 10 | tee "$out/table.txt"
# the renderer's own spread: one frame drawn again and again (what no selector can remove)
build/samples/walkthrough/tcrwalk --scene "$out/scene.txt" --calibration "$out/calibration.txt" --budget-ms "$budget" \
  --frames "$frames" --noise-test 200 | tee "$out/noise.txt"
scripts/plot-walk.py "$out/run" --budget-ms "$budget"
echo "walkthrough: table $out/table.txt, noise test $out/noise.txt, CSV and plots in $out/run/, screenshots in $out/run/shots/"
