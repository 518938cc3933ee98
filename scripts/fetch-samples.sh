#!/usr/bin/env bash
# Copies real sample meshes from Debian's packages into data/ (git-ignored):
#   data/meshes/   libcgal-demo's data tarball: fandisk.off, bunny00.off and a few more
#   data/assimp/   assimp-testmodels: glTF2 (including its broken cases), OBJ, PLY, OFF, STL
# The packages are installed by scripts/install-deps.sh.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
data="$root/data"
cgal_tar=/usr/share/doc/libcgal-demo/data.tar.gz
assimp=/usr/share/assimp/models
for need in "$cgal_tar" "$assimp/glTF2"; do
  if [ ! -e "$need" ]; then
    echo "fetch-samples: $need is missing: run scripts/install-deps.sh first (packages libcgal-demo, assimp-testmodels)" >&2
    exit 1
  fi
done
mkdir -p "$data/meshes" "$data/assimp"
meshes=(bunny00.off fandisk.off elephant.off cow.off mushroom.off eight.off cross.off)
members=()
for m in "${meshes[@]}"; do
  [ -s "$data/meshes/$m" ] || members+=("data/meshes/$m")
done
if [ ${#members[@]} -gt 0 ]; then
  tar -xzf "$cgal_tar" -C "$data/meshes" --strip-components=2 "${members[@]}"
fi
for dir in glTF2 OBJ PLY OFF STL; do
  [ -d "$data/assimp/$dir" ] || cp -r "$assimp/$dir" "$data/assimp/$dir"
done
echo "fetch-samples: $(find "$data" -type f | wc -l) files in $data"
