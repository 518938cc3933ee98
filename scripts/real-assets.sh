#!/usr/bin/env bash
# The real-asset benchmark: every asset (the glTF2 and OBJ samples of Debian's assimp-testmodels
# with more than 500 triangles, seven of its Collada and FBX models converted to glTF by assimp,
# and meshes written here as exporters write them: a UV sphere with
# its seam column and pole fans, and the cow unindexed and flat-shaded) simplified by tombuild and
# by the current gltfpack (npm, 1.3: its default, -sv and -sa, with -noq so that quantization adds
# no error) at 50%, 25% and 10% of the triangles, and each tool's floor (tomextract --fraction 0
# --below-floor; gltfpack -si 0 -sa) and TOM's usable floor (tomextract --fraction 0: where the
# mean error leaves 1%). TOM's level is taken at gltfpack's count (tomextract --scene-budget --below-floor: the
# triangles drawn, instances counted), and both are measured by tomerr in world space (node
# transforms applied) against the source: two-sided mean and Hausdorff distance (% of the
# diagonal), normal and texture-coordinate deviation.
# Writes the results as JSON lines (build/real-assets/results.jsonl) and the section "Real assets
# against gltfpack" of docs/PERFORMANCE.md (scripts/bench.sh keeps it when it rewrites the file).
# Usage: scripts/real-assets.sh [ASSET...]
#   TOM_TOMBUILD=PATH measures another tombuild (an older build, for a before-and-after table);
#   TOM_PERFORMANCE=FILE writes the section there instead of docs/PERFORMANCE.md
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
tools="$root/build/tools"
pack="$root/.tools/node_modules/gltfpack-current/cli.js"
[ -x "$tools/tombuild" ] || "$root/scripts/build.sh"
[ -f "$root/data/meshes/bunny00.off" ] || "$root/scripts/fetch-samples.sh"
[ -f "$pack" ] || "$root/scripts/install-deps.sh"
work="$root/build/real-assets"
rm -rf "$work"; mkdir -p "$work/generated"

# the exporter-written meshes
/usr/bin/python3 - "$root/data/meshes/cow.off" "$work/generated" <<'EOF'
import math, sys
off, out = sys.argv[1], sys.argv[2]
tokens = open(off).read().split()
nv, nf = int(tokens[1]), int(tokens[2])
V = [tuple(float(x) for x in tokens[4 + 3 * i:7 + 3 * i]) for i in range(nv)]
at = 4 + 3 * nv
F = []
for _ in range(nf):
    F.append(tuple(int(x) for x in tokens[at + 1:at + 4])); at += 4
def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def cross(a, b): return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
with open(out + '/cow-unindexed.obj', 'w') as f:
    for t in F:
        for v in t: f.write('v %.7g %.7g %.7g\n' % V[v])
    for j in range(len(F)): f.write('f %d %d %d\n' % (3 * j + 1, 3 * j + 2, 3 * j + 3))
with open(out + '/cow-flat.obj', 'w') as f:
    for t in F:
        for v in t: f.write('v %.7g %.7g %.7g\n' % V[v])
    for t in F:
        n = cross(sub(V[t[1]], V[t[0]]), sub(V[t[2]], V[t[0]])); l = math.sqrt(sum(x * x for x in n)) or 1
        f.write('vn %.6f %.6f %.6f\n' % tuple(x / l for x in n))
    for j in range(len(F)): f.write('f %d//%d %d//%d %d//%d\n' % (3 * j + 1, j + 1, 3 * j + 2, j + 1, 3 * j + 3, j + 1))
# a UV sphere of 48 x 96 quads as SphereGeometry writes it: columns 0..96 (the last a copy of the
# first at u = 1, computed from 2 pi), each pole a fan of 96 copies
rings, segs = 48, 96
with open(out + '/uv-sphere.obj', 'w') as f:
    index = {}
    for i in range(rings + 1):
        cols = segs if i in (0, rings) else segs + 1
        for j in range(cols):
            phi, theta = math.pi * i / rings, 2 * math.pi * j / segs
            r = 0.0 if i in (0, rings) else math.sin(phi)
            p = (r * math.cos(theta), r * math.sin(theta), math.cos(phi))
            u = (j + 0.5) / segs if i in (0, rings) else j / segs
            f.write('v %.9g %.9g %.9g\nvn %.9g %.9g %.9g\nvt %.9g %.9g\n' % (p + p + (u, 1 - i / rings)))
            index[i, j] = len(index) + 1
    def corner(k): return '%d/%d/%d' % (k, k, k)
    for i in range(rings):
        for j in range(segs):
            a, d = index[i, j], index.get((i, j + 1))
            b, c = index[i + 1, j], index.get((i + 1, j + 1))
            if i == 0: f.write('f %s %s %s\n' % (corner(a), corner(b), corner(c)))
            elif i + 1 == rings: f.write('f %s %s %s\n' % (corner(a), corner(b), corner(d)))
            else: f.write('f %s %s %s\nf %s %s %s\n' % (corner(a), corner(b), corner(c), corner(a), corner(c), corner(d)))
EOF

assets=("$@")
if [ ${#assets[@]} -eq 0 ]; then
  a="$root/data/assimp"
  assets=("$a/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb" "$a/glTF2/ClearCoat-glTF/ClearCoatTest.gltf"
          "$a/OBJ/spider.obj" "$a/OBJ/WusonOBJ.obj" "$a/OBJ/regr01.obj"
          "$work/generated/uv-sphere.obj" "$work/generated/cow-unindexed.obj" "$work/generated/cow-flat.obj")
  # Collada and FBX models as assimp converts them (scripts/fetch-samples.sh): Khronos' Duck, a
  # textured human, a logo on a floor, three teapots, a cylindrically mapped globe, the spider in
  # 19 meshes, a skinned and animated character
  c="$a/converted"
  for m in Collada/duck-dae Collada/human-zae Collada/COLLADA-dae Collada/teapots-dae Collada/earthCylindrical-dae FBX/spider-fbx \
           FBX/animation_with_skeleton-fbx; do
    [ -f "$c/$m.glb" ] && assets+=("$c/$m.glb")
  done
fi

# One JSON line from tomerr's measures of a tool's level (one, or one per pose): the mean of their
# mean errors, normal and texture-coordinate deviations, their largest Hausdorff distance.
record() {  # asset tool mode ratio json...
  /usr/bin/python3 -c "
import json, statistics, sys
d = [json.loads(x) for x in sys.argv[5:]]
def mean(f): return None if any(f(x) is None for x in d) else statistics.mean(f(x) for x in d)
print(json.dumps({'asset': sys.argv[1], 'tool': sys.argv[2], 'mode': sys.argv[3], 'ratio': float(sys.argv[4]), 'triangles': d[0]['simplified_triangles'],
                  'source_triangles': d[0]['original_triangles'], 'mean': mean(lambda x: x['mean']), 'hausdorff': max(x['hausdorff'] for x in d),
                  'normal_degrees': mean(lambda x: x['attributes']['normal_mean_degrees']), 'uv': mean(lambda x: x['attributes']['uv_mean'])}))" \
    "$(basename "$1")" "$2" "$3" "$4" "${@:5}" >> "$work/results.jsonl"
}
# a tool's level of an asset measured against the source
measure() {  # asset tool mode ratio file; fails (naming the file) when tomerr cannot read it
  local json
  json="$("$tools/tomerr" "$1" "$5" --json)" || { echo "real-assets: $5 not measured" >&2; return 1; }
  record "$1" "$2" "$3" "$4" "$json"
}
# A skinned and animated asset is also measured as it moves: the source and a level posed by the
# source's first animation at eight times (scripts/pose.py), each pair measured by tomerr, as one
# JSON line with the mode "posed-MODE". In the bind pose alone a tool blind to skinning can look
# exact (gltfpack merges vertices that bend apart once joints turn).
poses() {  # source glb level prefix: true when the asset moves (prefix-0.obj ... written)
  local status=0
  /usr/bin/python3 "$root/scripts/pose.py" "$1" "$2" "$3" || status=$?
  [ "$status" -eq 0 ] || { [ "$status" -eq 3 ] || { echo "real-assets: $2 not posed" >&2; exit 1; }; return 1; }
}
measure_posed() {  # asset tool mode ratio level; the source's poses at $out/posed-source-K.obj
  local k jsons=()
  poses "$1" "$5" "$out/posed-level" || { echo "real-assets: $5 has no skinned node where its source moves: not posed" >&2; return 1; }
  for k in 0 1 2 3 4 5 6 7; do
    jsons+=("$("$tools/tomerr" "$out/posed-source-$k.obj" "$out/posed-level-$k.obj" --json)") || { echo "real-assets: $5 posed not measured" >&2; return 1; }
  done
  record "$1" "$2" "posed-$3" "$4" "${jsons[@]}"
}
triangles_of() { "$tools/tomerr" "$1" "$1" --json --samples-per-face 0.01 | /usr/bin/python3 -c "import json,sys; print(json.load(sys.stdin)['original_triangles'])"; }

for src in "${assets[@]}"; do
  name="$(basename "${src%.*}")"
  out="$work/$name"; mkdir -p "$out"
  "${TOM_TOMBUILD:-$tools/tombuild}" "$src" -o "$out" -q
  tom="$out/$name.tom"
  # floors
  "$tools/tomextract" "$tom" --fraction 0 --below-floor -o "$out/tom-floor.glb" --texture-dir "$(dirname "$src")" >/dev/null
  measure "$src" tom floor 0 "$out/tom-floor.glb"
  "$tools/tomextract" "$tom" --fraction 0 -o "$out/tom-usable.glb" --texture-dir "$(dirname "$src")" >/dev/null
  measure "$src" tom usable 0 "$out/tom-usable.glb"
  # (gltfpack may remove a whole asset at its floor: a file without meshes, not compared)
  if node "$pack" -i "$src" -o "$out/gltfpack-floor.glb" -noq -si 0 -sa >/dev/null 2>&1 && measure "$src" gltfpack floor-sa 0 "$out/gltfpack-floor.glb"; then
    floor_count="$(triangles_of "$out/gltfpack-floor.glb")"
    "$tools/tomextract" "$tom" --below-floor --scene-budget "$floor_count" -o "$out/tom-at-floor.glb" --texture-dir "$(dirname "$src")" >/dev/null 2>&1
    measure "$src" tom at-floor-sa 0 "$out/tom-at-floor.glb"
    "$tools/tomextract" "$tom" --below-floor --scene-budget "$floor_count" --refit -o "$out/tom-at-floor-refit.glb" --texture-dir "$(dirname "$src")" >/dev/null 2>&1
    measure "$src" tom refit-floor-sa 0 "$out/tom-at-floor-refit.glb"
  fi
  # levels: gltfpack's, and TOM's at the same drawn count (an animated skinned asset posed too)
  moves=false
  if [[ "$src" == *.glb ]] && poses "$src" "$src" "$out/posed-source"; then moves=true; fi
  for ratio in 0.5 0.25 0.1; do
    for mode in default sv sa; do
      flag=(); [ "$mode" = default ] || flag=("-$mode")
      g="$out/gltfpack-$mode-$ratio.glb"
      node "$pack" -i "$src" -o "$g" -noq -si "$ratio" "${flag[@]}" >/dev/null 2>&1 || { echo "gltfpack failed on $src" >&2; continue; }
      measure "$src" gltfpack "$mode" "$ratio" "$g" || continue
      count="$(triangles_of "$g")"
      t="$out/tom-$mode-$ratio.glb"
      "$tools/tomextract" "$tom" --below-floor --scene-budget "$count" -o "$t" --texture-dir "$(dirname "$src")" >/dev/null 2>&1
      measure "$src" tom "at-$mode" "$ratio" "$t"
      # the same level written on its own, its vertices re-fitted (as -sv moves gltfpack's)
      "$tools/tomextract" "$tom" --below-floor --scene-budget "$count" --refit -o "${t%.glb}-refit.glb" --texture-dir "$(dirname "$src")" >/dev/null 2>&1
      measure "$src" tom "refit-$mode" "$ratio" "${t%.glb}-refit.glb"
      if $moves; then  # (a level that cannot be posed is named and compared in the bind pose)
        measure_posed "$src" gltfpack "$mode" "$ratio" "$g" || true
        measure_posed "$src" tom "at-$mode" "$ratio" "$t" || true
        measure_posed "$src" tom "refit-$mode" "$ratio" "${t%.glb}-refit.glb" || true
      fi
    done
  done
  echo "$name: measured" >&2
done

/usr/bin/python3 - "$work/results.jsonl" "${TOM_PERFORMANCE:-$root/docs/PERFORMANCE.md}" <<'EOF'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
doc = sys.argv[2]
def find(asset, tool, mode, ratio):
    for r in rows:
        if r['asset'] == asset and r['tool'] == tool and r['mode'] == mode and r['ratio'] == ratio: return r
def fmt(x, p=4): return '-' if x is None else ('%.' + str(p) + 'g') % x
L = ['## Real assets against gltfpack', '',
     '`scripts/real-assets.sh`: each asset built by tombuild (defaults) and simplified by the current gltfpack (npm) with `-noq`',
     'at 50%, 25% and 10% (`-si`) in its default mode, `-sv` and `-sa`; TOM\'s level is extracted at the count gltfpack reached',
     '(`tomextract --scene-budget --below-floor`, triangles drawn), and both are measured by `tomerr` in world space against the source:',
     'two-sided mean and Hausdorff distance in % of the diagonal, mean normal deviation in degrees, mean texture-coordinate',
     'deviation. Floors: `tomextract --fraction 0 --below-floor` and `gltfpack -si 0 -sa`; TOM\'s usable floor (where its',
     'stored mean error leaves 1% of the diagonal, the level its selections stop at): `tomextract --fraction 0`. "--refit": the',
     'same level written on its own with its vertices re-fitted (`tomextract --refit`, as `-sv` moves gltfpack\'s): what a',
     'discrete level exported from TOM is; the runtime\'s levels, prefixes of one vertex array, are the columns before.',
     'A skinned asset with an animation is also measured as it moves ("posed"): the source and each level posed by the',
     'source\'s first animation at eight times over it (`scripts/pose.py`), the mean over the poses of the mean error and',
     'deviations, the largest Hausdorff distance; its medians take the posed figures (in the bind pose a simplifier blind to',
     'skinning can look exact: gltfpack merges vertices that bend apart once the joints turn).', '',
     '| asset | triangles | mode, ratio | count | mean TOM / gltfpack | Hausdorff TOM / gltfpack | normals TOM / gltfpack | uv TOM / gltfpack | --refit: mean, Hausdorff, normals, uv |',
     '|---|---:|---|---:|---:|---:|---:|---:|---:|']
ratios = {}
def row(asset, label, count_note, t, g, f):
    return '| %s | %d | %s | %d%s / %d | %s / %s | %s / %s | %s / %s | %s / %s | %s |' % (
        asset, g['source_triangles'], label, t['triangles'], count_note, g['triangles'], fmt(t['mean']), fmt(g['mean']),
        fmt(t['hausdorff']), fmt(g['hausdorff']), fmt(t['normal_degrees'], 3), fmt(g['normal_degrees'], 3), fmt(t['uv'], 3), fmt(g['uv'], 3),
        '%s, %s, %s, %s' % (fmt(f['mean']), fmt(f['hausdorff']), fmt(f['normal_degrees'], 3), fmt(f['uv'], 3)) if f else '-')
for asset in dict.fromkeys(r['asset'] for r in rows):
    for ratio in (0.5, 0.25, 0.1):
        for mode in ('default', 'sv', 'sa'):
            g, t, f = find(asset, 'gltfpack', mode, ratio), find(asset, 'tom', 'at-' + mode, ratio), find(asset, 'tom', 'refit-' + mode, ratio)
            if not g or not t: continue
            reached = t['triangles'] <= 1.02 * g['triangles']  # else TOM stopped above gltfpack's count: not compared
            # an animated skinned asset is compared as it moves (measure_posed), its bind pose shown too
            pg, pt, pf = find(asset, 'gltfpack', 'posed-' + mode, ratio), find(asset, 'tom', 'posed-at-' + mode, ratio), find(asset, 'tom', 'posed-refit-' + mode, ratio)
            compared = (pt, pg, pf) if pg and pt else (t, g, f)
            if reached:
                for key in ('mean', 'hausdorff', 'normal_degrees', 'uv'):
                    for which, x in (('', compared[0]), ('refit', compared[2])):
                        if x and compared[1][key] is not None and x[key] is not None:
                            ratios.setdefault((mode, ratio, key, which), []).append(x[key] / compared[1][key] if compared[1][key] > 0 else 1.0)
            label = '%s %d%%' % (mode, ratio * 100)
            L.append(row(asset, label + (', bind pose' if pg and pt else ''), '' if reached else ' (floor)', t, g, f))
            if pg and pt: L.append(row(asset, label + ', posed', '' if reached else ' (floor)', pt, pg, pf))
L += ['', 'Floors: the coarsest level each tool reaches, TOM\'s usable floor, and TOM\'s level at gltfpack -sa\'s floor count.', '',
      '| asset | triangles | TOM floor | mean | TOM usable floor | mean | gltfpack -sa floor | mean | TOM there | mean | Hausdorff TOM / gltfpack | --refit: mean, Hausdorff |',
      '|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|']
floor_ratios = {}
for asset in dict.fromkeys(r['asset'] for r in rows):
    t, u, g, a, f = (find(asset, 'tom', 'floor', 0), find(asset, 'tom', 'usable', 0), find(asset, 'gltfpack', 'floor-sa', 0),
                     find(asset, 'tom', 'at-floor-sa', 0), find(asset, 'tom', 'refit-floor-sa', 0))
    if t and u and g and a:
        for which, x in (('', a), ('refit', f)):
            if x and g['mean']: floor_ratios.setdefault(which, []).append(x['mean'] / g['mean'])
        L.append('| %s | %d | %d | %s | %d | %s | %d | %s | %d | %s | %s / %s | %s |' % (
            asset, t['source_triangles'], t['triangles'], fmt(t['mean']), u['triangles'], fmt(u['mean']), g['triangles'], fmt(g['mean']),
            a['triangles'], fmt(a['mean']), fmt(a['hausdorff']), fmt(g['hausdorff']), '%s, %s' % (fmt(f['mean']), fmt(f['hausdorff'])) if f else '-'))
if floor_ratios:
    L += ['', 'At gltfpack -sa\'s floor count, TOM\'s mean / gltfpack\'s: median %s, %s with --refit.' % tuple(
        '%.2f' % statistics.median(floor_ratios[w]) if w in floor_ratios else '-' for w in ('', 'refit'))]
L += ['', 'Medians over the assets where TOM reached gltfpack\'s count, TOM / gltfpack (below 1: TOM\'s error is smaller; uv over',
      'the assets where both have texture coordinates):', '',
      '| mode, ratio | assets | mean | Hausdorff | normals | uv | --refit: mean | Hausdorff | normals | uv |', '|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|']
for mode, ratio in sorted({(m, r) for m, r, _, _ in ratios}, key=lambda mr: (mr[0], -mr[1])):
    column = lambda key, which='': '%.2f' % statistics.median(ratios[(mode, ratio, key, which)]) if (mode, ratio, key, which) in ratios else '-'
    L.append('| %s %d%% | %d | %s | %s | %s | %s | %s | %s | %s | %s |' % (
        mode, ratio * 100, len(ratios[(mode, ratio, 'mean', '')]), column('mean'), column('hausdorff'), column('normal_degrees'), column('uv'),
        column('mean', 'refit'), column('hausdorff', 'refit'), column('normal_degrees', 'refit'), column('uv', 'refit')))
L.append('')
section = '\n'.join(L)
text = open(doc).read()
start = text.find('## Real assets against gltfpack')
if start < 0:
    at = text.find('## Walkthrough')
    text = text[:at] + section + '\n' + text[at:] if at >= 0 else text.rstrip('\n') + '\n\n' + section
else:
    end = text.find('\n## ', start + 1)
    text = text[:start] + section + ('\n' + text[end + 1:] if end >= 0 else '')
open(doc, 'w').write(text)
print(section)
EOF
