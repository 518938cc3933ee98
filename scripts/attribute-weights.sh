#!/usr/bin/env bash
# Measures the attribute term of the predicates: for each attribute weight given (default 0 and
# 1), builds bunny, fandisk, elephant, ClearCoatTest (glTF, UVs) and spider (OBJ, UVs) and prints,
# per mesh at 25/10/5/2% of the triangles: Metro mean error (% of the diagonal) / mean normal
# deviation (degrees) / mean UV displacement (texture units; - without UVs). Multi-mesh files are
# averaged weighted by triangles.
# usage: scripts/attribute-weights.sh [WEIGHT...] [--predicate quadric|memoryless]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
predicate=quadric
weights=()
while [ $# -gt 0 ]; do
  case "$1" in
    --predicate) predicate="$2"; shift 2 ;;
    *) weights+=("$1"); shift ;;
  esac
done
[ ${#weights[@]} -gt 0 ] || weights=(0 1)
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
d="$root/data"
for w in "${weights[@]}"; do
  "$root/build/tools/tombuild" "$d/meshes/bunny00.off" "$d/meshes/fandisk.off" "$d/meshes/elephant.off" \
    "$d/assimp/glTF2/ClearCoat-glTF/ClearCoatTest.gltf" "$d/assimp/OBJ/spider.obj" -o "$work/$w" --report-json "$work/$w/r" \
    --levels 25,10,5,2 --attribute-weight "$w" --predicate "$predicate" --no-error-curve -q -j 2 >/dev/null
  /usr/bin/python3 - "$work/$w/r" "$w" "$predicate" <<'PY'
import glob, json, sys
print('%s, attribute weight %s: mean error %% / normal deg / uv at 25, 10, 5, 2%%' % (sys.argv[3], sys.argv[2]))
for f in sorted(glob.glob(sys.argv[1] + '/*.json')):
    meshes = json.load(open(f))['meshes']
    total = sum(m['triangles'] for m in meshes)
    cells = []
    for i in range(4):
        geo = sum(m['levels'][i]['error']['mean'] * m['triangles'] for m in meshes) / total
        normal = sum((m['levels'][i]['attributes']['normal_mean_degrees'] or 0) * m['triangles'] for m in meshes) / total
        uv = [m['levels'][i]['attributes']['uv_mean'] for m in meshes if m['levels'][i]['attributes']['uv_mean'] is not None]
        cells.append('%.4f/%.2f/%s' % (geo, normal, '%.4f' % (sum(uv) / len(uv)) if uv else '-'))
    print('  %-14s %s' % (f.split('/')[-1][:-5][:14], '  '.join(cells)))
PY
done
