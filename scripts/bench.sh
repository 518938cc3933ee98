#!/usr/bin/env bash
# Measures the toolkit against its references in one run and writes docs/PERFORMANCE.md:
# tombench (build against meshopt_simplify, extraction against memcpy) on the sample meshes and a
# generated 2M-triangle sphere, tcrbench (every selector at 100 to 100k objects), and the
# conversion and report times of tombuild, one extraction through the C++, C and Python APIs
# (scripts/bench-bindings.py), and tomextract -c's bytes against the current gltfpack's.
# Stamped with the commit, the date and the CPU. The sections "Real assets against gltfpack" and
# "Streaming" are scripts/real-assets.sh's and bench-stream.sh's, kept as they last wrote them.
# Usage: scripts/bench.sh [--quick] [--walk] [--scale | --large-report] [OUT.md]
#   --quick: bunny00 and fandisk only, fewer repeats; --walk: also the walkthrough at a 40 ms
#   budget (scripts/walkthrough.sh, a few minutes), its table and the renderer's noise test;
#   --scale: also scripts/bench-scale.sh (a 10M-triangle conversion and a 2M report, about
#   5 minutes and 3 GB); --large-report: --scale with the 10M-triangle mesh's report too
#   (about 8 minutes more and 6 GB)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
quick=0; walk=0; scale=0; large_report=""
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1; shift ;;
    --walk) walk=1; shift ;;
    --scale) scale=1; shift ;;
    --large-report) scale=1; large_report=--large-report; shift ;;
    *) break ;;
  esac
done
out="${1:-$root/docs/PERFORMANCE.md}"
[ -x "$root/build/tools/tombench" ] || "$root/scripts/build.sh"
[ -f "$root/data/meshes/bunny00.off" ] || "$root/scripts/fetch-samples.sh"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
tools="$root/build/tools"
repeats=5; [ $quick = 1 ] && repeats=3

echo "bench: tombench" >&2
meshes=(bunny00 fandisk elephant)
[ $quick = 1 ] && meshes=(bunny00 fandisk)
for m in "${meshes[@]}"; do
  "$tools/tombench" "$root/data/meshes/$m.off" --json -r "$repeats" >> "$work/tombench.jsonl"
  "$tools/tombench" "$root/data/meshes/$m.off" --json -r "$repeats" --attribute-weight 0 --build-threads 1 | \
    /usr/bin/python3 -c 'import json,sys; d=json.loads(sys.stdin.read()); d["variant"]="geometry only, 1 thread"; print(json.dumps(d))' >> "$work/tombench.jsonl"
done
[ $quick = 1 ] || "$tools/tombench" "$root/data/meshes/bunny00.off" --generated 2000000 --json -r 3 >> "$work/tombench.jsonl"

echo "bench: tcrbench" >&2
objects="100 1000 10000 100000"; [ $quick = 1 ] && objects="100 1000 10000"
# shellcheck disable=SC2086
"$tools/tcrbench" --objects $objects --json > "$work/tcrbench.jsonl"

echo "bench: bindings" >&2
"$tools/tombuild" "$root/data/meshes/bunny00.off" -o "$work/bindings" -q
/usr/bin/python3 "$root/scripts/bench-bindings.py" "$work/bindings/bunny00.tom" --json > "$work/bindings.jsonl"

echo "bench: compressed glTF" >&2
pack="$root/.tools/node_modules/gltfpack-current/cli.js"
[ -f "$pack" ] || "$root/scripts/install-deps.sh" >/dev/null
size() { stat -c %s "$1"; }
for m in bunny00 fandisk elephant 2CylinderEngine; do
  src="$root/data/meshes/$m.off"; [ "$m" = 2CylinderEngine ] && src="$root/data/assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"
  p="$work/packed/$m"
  "$tools/tombuild" "$src" -o "$work/packed" -q --no-error-curve
  # the same mesh for both tools: the .tom's finest level as plain glTF
  "$tools/tomextract" "$p.tom" --lods 100 -o "$p.glb" >/dev/null
  "$tools/tomextract" "$p.tom" --lods 100 -c -o "$p-c.glb" >/dev/null
  "$tools/tomextract" "$p.tom" --lods 100,50,25,10 -c -o "$p-chain.glb" >/dev/null
  for o in c cc; do node "$pack" -i "$p.glb" -o "$p-gltfpack-$o.glb" -$o >/dev/null; done
  triangles=$("$tools/tominfo" "$p.tom" --json | /usr/bin/python3 -c 'import json,sys; print(sum(m["triangles"] for m in json.load(sys.stdin)["meshes"]))')
  echo "{\"mesh\": \"$m\", \"triangles\": $triangles, \"plain\": $(size "$p.glb"), \"tom_c\": $(size "$p-c.glb"), \"chain_c\": $(size "$p-chain.glb"), \"gltfpack_c\": $(size "$p-gltfpack-c.glb"), \"gltfpack_cc\": $(size "$p-gltfpack-cc.glb")}" >> "$work/packed.jsonl"
done

echo "bench: tombuild" >&2
for m in bunny00 fandisk; do
  "$tools/tombuild" "$root/data/meshes/$m.off" -o "$work/tom" --report-json "$work/reports" -q
done
"$tools/tombuild" "$root/data/assimp" "$root/data/meshes" -o "$work/folders" -q -j 2 >/dev/null 2>&1 || true
start=$(date +%s.%N); "$tools/tombuild" "$root/data/assimp" "$root/data/meshes" -o "$work/folders2" -q -j 2 >/dev/null 2>&1 || true
folders_s=$(echo "$(date +%s.%N) - $start" | bc)
start=$(date +%s.%N); "$tools/tombuild" "$root/data/assimp" "$root/data/meshes" -o "$work/folders3" -q -j 2 --no-error-curve >/dev/null 2>&1 || true
folders_nocurve_s=$(echo "$(date +%s.%N) - $start" | bc)

scale_table="$work/scale-table.txt"; : > "$scale_table"
if [ $scale = 1 ]; then
  echo "bench: bench-scale" >&2
  bash "$root/scripts/bench-scale.sh" $large_report > "$scale_table"
fi
walk_table="$work/walk-table.txt"; : > "$walk_table"
if [ $walk = 1 ]; then
  echo "bench: walkthrough" >&2
  bash "$root/scripts/walkthrough.sh" 40 300 >/dev/null
  cp "$root/out/walk/table.txt" "$walk_table"
  cat "$root/out/walk/noise.txt" >> "$walk_table"
fi

commit="$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
[ -z "$(git -C "$root" status --porcelain 2>/dev/null)" ] || commit="$commit (with uncommitted changes)"
cpu="$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
/usr/bin/python3 - "$work" "$out" "$commit" "$cpu" "$(nproc)" "$folders_s" "$folders_nocurve_s" "$walk_table" "$scale_table" <<'PY'
import datetime, glob, json, os, sys
work, out, commit, cpu, cores, folders_s, folders_nocurve_s, walk_table, scale_table = sys.argv[1:10]
tb = [json.loads(l) for l in open(os.path.join(work, 'tombench.jsonl')) if l.strip()]
tc = [json.loads(l) for l in open(os.path.join(work, 'tcrbench.jsonl')) if l.strip()]
reports = {}
for p in sorted(glob.glob(os.path.join(work, 'reports', '*.json'))):
    r = json.load(open(p))
    for m in r['meshes']:
        reports[m['name']] = m
L = []
L.append('# Performance')
L.append('')
L.append('Generated by `scripts/bench.sh`; do not edit. Commit %s, %s, %s (%s cores).' %
         (commit, datetime.date.today().isoformat(), cpu, cores))
L.append('Every figure is measured in the same run as its reference; on a shared machine compare the')
L.append('ratios, not the times.')
L.append('')
L.append('## Build against meshopt_simplify')
L.append('')
L.append('`tombench MESH`: the TOM build (all levels at once) against `meshopt_simplify` to 1% of the')
L.append('triangles on one thread, medians of interleaved repeats.')
L.append('')
L.append('| mesh | triangles | build | threads | build ms | meshopt ms | ratio |')
L.append('|---|---:|---|---:|---:|---:|---:|')
for d in tb:
    L.append('| %s | %d | %s | %d | %.1f | %.1f | %.2fx |' % (d['mesh'], d['triangles'], d.get('variant', 'default (attributes)'),
             d['build_threads'], d['build_ms'], d['meshopt_ms'], d['build_over_meshopt']))
L.append('')
L.append('## Extraction against memcpy')
L.append('')
L.append('Index-buffer extraction at a fraction of the triangles, in triangles per second, and its time')
L.append('relative to a `memcpy` of the same output bytes: memcpy time / extraction time (1.0: as fast as copying the finished buffer).')
L.append('')
L.append('| mesh | fraction | triangles | Mtri/s | speed / memcpy |')
L.append('|---|---:|---:|---:|---:|')
for d in tb:
    if 'variant' in d: continue
    for e in d['extract']:
        L.append('| %s | %g%% | %d | %.0f | %.2f |' % (d['mesh'], 100 * e['fraction'], e['triangles'], e['tris_per_s'] / 1e6, e['memcpy_ratio']))
L.append('')
L.append('## Conversion and reports')
L.append('')
L.append('`tombuild MESH -o D --report-json D`: seconds as the report JSON gives them.')
L.append('')
L.append('| mesh | import s | build s | report s (7 levels and the error curve) | report / build |')
L.append('|---|---:|---:|---:|---:|')
for name, m in reports.items():
    L.append('| %s | %.3f | %.3f | %.3f | %.1fx |' % (name, m['import_seconds'], m['build_seconds'], m['report_seconds'], m['report_seconds'] / max(m['build_seconds'], 1e-9)))
L.append('')
L.append('The sample folders (`tombuild data/assimp data/meshes -j 2`): %.2f s; with `--no-error-curve`: %.2f s.' % (float(folders_s), float(folders_nocurve_s)))
L.append('')
L.append('## The C API and the Python package')
L.append('')
L.append('`scripts/bench-bindings.py`: one extraction of bunny00 into a preallocated buffer through each API,')
L.append('rounds alternating in one process (Python\'s `mesh.extract(vertices=n, out=out)`, then `tom::extract` and')
L.append('`tom_extract_u32` looped in the native module), median ns per call.')
L.append('')
L.append('| fraction | vertices | triangles | C++ ns | C ns | Python ns | C / C++ | Python - C++ (us) |')
L.append('|---:|---:|---:|---:|---:|---:|---:|---:|')
for d in [json.loads(l) for l in open(os.path.join(work, 'bindings.jsonl')) if l.strip()]:
    L.append('| %g | %d | %d | %.0f | %.0f | %.0f | %.3f | %.2f |' % (d['fraction'], d['vertices'], d['triangles'], d['cpp_ns'], d['c_ns'], d['python_ns'],
             d['c_over_cpp'], d['python_minus_cpp_us']))
L.append('')
L.append('## Compressed glTF against gltfpack')
L.append('')
L.append('`tomextract -c --lods 100` (KHR_mesh_quantization and EXT_meshopt_compression through Debian\'s meshoptimizer 0.18)')
L.append('against the current gltfpack (1.3, npm) with `-c` and `-cc` on the same mesh (the .tom\'s finest level as plain')
L.append('glTF), file bytes; the last column is a chain of four levels (100, 50, 25, 10%) in one compressed file.')
L.append('')
L.append('| asset | triangles | plain | tomextract -c | gltfpack -c | gltfpack -cc | -c / gltfpack -cc | chain of 4, -c |')
L.append('|---|---:|---:|---:|---:|---:|---:|---:|')
for d in [json.loads(l) for l in open(os.path.join(work, 'packed.jsonl')) if l.strip()]:
    L.append('| %s | %d | %d | %d | %d | %d | %.3f | %d |' % (d['mesh'], d['triangles'], d['plain'], d['tom_c'], d['gltfpack_c'], d['gltfpack_cc'],
             d['tom_c'] / d['gltfpack_cc'], d['chain_c']))
L.append('')
L.append('## Selectors')
L.append('')
L.append('`tcrbench`: seeded random frames, the budget a quarter of full detail; time per object per')
L.append('frame, and the certified gap of barrier and exact.')
L.append('')
L.append('| selector | objects | ns / object | benefit / exact\'s | predicted / budget | gap |')
L.append('|---|---:|---:|---:|---:|---:|')
exact = {d['objects']: d['benefit'] for d in tc if d['selector'] == 'exact'}
for d in tc:
    gap = '-' if d['gap'] is None else '%.1e' % d['gap']
    L.append('| %s | %d | %.0f | %.5f | %.4f | %s |' % (d['selector'], d['objects'], d['ns_per_object'], d['benefit'] / exact[d['objects']],
             d['predicted_ms'] / d['budget_ms'], gap))
L.append('')
scale = open(scale_table).read().strip()
L.append('## Conversion at scale')
L.append('')
L.append(scale if scale else 'Not measured in this run (`scripts/bench.sh --scale`).')
L.append('')
walk = open(walk_table).read().strip()
# the real-asset and streaming sections are scripts/real-assets.sh's and bench-stream.sh's
# (minutes of gltfpack and tomerr runs): kept as they are
try:
    old = open(out).read()
except OSError:
    old = ''
for title, script in (('## Real assets against gltfpack', 'scripts/real-assets.sh'), ('## Streaming', 'scripts/bench-stream.sh')):
    start = old.find(title)
    if start >= 0:
        end = old.find('\n## ', start + 1)
        L.extend(old[start:end if end >= 0 else len(old)].rstrip('\n').split('\n'))
        L.append('')
    else:
        L.extend([title, '', 'Not measured in this run (`' + script + '`).', ''])
L.append('## Walkthrough')
L.append('')
if walk:
    L.append('`scripts/walkthrough.sh 40 300`: 300 instances (the spider among them textured) and a far ring of 200')
    L.append('drawn headless by llvmpipe at a 40 ms budget, the table in the form of Funkhouser\'s Table 1 (`exact` and')
    L.append('`greedy` with the whole menu: levels smooth, flat or texture-mapped, simple and meshed imposters;')
    L.append('`exact-levels` is exact on the smooth levels alone, in the plain colour, as `static`, `stress` and')
    L.append('`barrier` draw; the selectors take the path together, frame by frame), then the renderer\'s own')
    L.append('spread (`--noise-test`).')
    L.append('')
    L.append('```')
    L.append(walk)
    L.append('```')
else:
    L.append('Not measured in this run (`scripts/bench.sh --walk`).')
L.append('')
open(out, 'w').write('\n'.join(L))
print('bench: wrote', out)
PY
