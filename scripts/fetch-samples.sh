#!/usr/bin/env bash
# Copies real sample meshes from Debian's packages into data/ (git-ignored):
#   data/meshes/   libcgal-demo's data tarball: fandisk.off, bunny00.off and a few more
#   data/assimp/   assimp-testmodels: glTF2 (including its broken cases), OBJ, PLY, OFF, STL
#   data/assimp/converted/   its Collada and FBX models, converted to .glb by assimp-utils (as a
#                  user without a converter of their own would); those assimp cannot read are listed
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
# Collada and FBX through assimp's glTF exporter: NAME-EXT.glb (duck.dae and duck.zae both exist)
if command -v assimp >/dev/null 2>&1; then
  failed=()
  for src in "$assimp"/Collada/* "$assimp"/FBX/* "$assimp"/FBX/embedded_ascii/*; do
    ext="${src##*.}"; ext="${ext,,}"
    case "$ext" in dae|zae|fbx) ;; *) continue ;; esac
    dir="$data/assimp/converted/$(basename "$(dirname "$src")")"
    out="$dir/$(basename "${src%.*}")-$ext.glb"
    [ -s "$out" ] && continue
    mkdir -p "$dir"
    # written aside and renamed: an interrupted run leaves no half-written model
    if timeout 120 assimp export "$src" "$out.part" -fglb2 >/dev/null 2>&1 && [ -s "$out.part" ]; then
      mv "$out.part" "$out"
    else
      rm -f "$out.part"; failed+=("$(basename "$src")")
    fi
  done
  [ ${#failed[@]} -eq 0 ] || echo "fetch-samples: assimp cannot convert ${failed[*]} (deliberately broken samples among them)" >&2
else
  echo "fetch-samples: assimp not found, Collada and FBX samples not converted: run scripts/install-deps.sh (assimp-utils)" >&2
fi
echo "fetch-samples: $(find "$data" -type f | wc -l) files in $data"
