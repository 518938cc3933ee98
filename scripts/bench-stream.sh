#!/usr/bin/env bash
# The error against bytes received: for each mesh, the two-sided Metro mean (tomerr, % of the
# diagonal) of what the first B bytes of its streamed .tom decode to (tombuild --stream,
# tomextract --bytes B), against a glTF LOD chain (levels of 1, 5, 25 and 100% of the triangles,
# each compressed by the current gltfpack's -cc, fetched coarsest first: after B bytes the finest
# level wholly received; a level's bytes are its .gltf and .bin, the images not counted), at
# every chunk boundary of the stream and every level boundary of the chain, and against one
# gltfpack -cc level; then
# tomstreambench's decode speeds, natively and in headless chromium (scripts/bench-web.sh). Writes the section "Streaming" of docs/PERFORMANCE.md (kept by
# scripts/bench.sh when it rewrites the file) with its plot docs/images/stream.png, and
# out/stream/stream.json. TOM_PERFORMANCE=FILE writes the section there instead.
# Usage: scripts/bench-stream.sh [MESH...]   (default: bunny00, the textured spider and a generated
# bumpy sphere of 2M triangles, tombench --write-generated)
# The chain's errors are measured on its levels quantized by gltfpack as -cc quantizes them, but
# without the codecs (gltfpack 1.3's -cc output uses codecs newer than Debian's decoders that
# tomerr reads with), the stream's on what it decodes to: both with their quantization.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
tools="$root/build/tools"
[ -x "$tools/tomstreambench" ] || "$root/scripts/build.sh"
[ -f "$root/data/meshes/bunny00.off" ] || "$root/scripts/fetch-samples.sh"
pack="$root/.tools/node_modules/gltfpack-current/cli.js"
[ -f "$pack" ] || { echo "bench-stream: the current gltfpack is missing: run scripts/install-deps.sh" >&2; exit 1; }
meshes=("$@")
out="$root/out/stream"; mkdir -p "$out"
if [ ${#meshes[@]} -eq 0 ]; then
  [ -f "$out/sphere2m.ply" ] || "$tools/tombench" "$root/data/meshes/bunny00.off" --generated 2000000 --write-generated "$out/sphere2m.ply" > /dev/null
  meshes=("$root/data/meshes/bunny00.off" "$root/data/assimp/OBJ/spider.obj" "$out/sphere2m.ply")
fi
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT

for mesh in "${meshes[@]}"; do
  name="$(basename "${mesh%.*}")"
  echo "bench-stream: $name" >&2
  "$tools/tombuild" "$mesh" -o "$work/stream" -q --stream --force
  "$tools/tombuild" "$mesh" -o "$work/plain" -q --force
  "$tools/tominfo" --json "$work/stream/$name.tom" > "$work/$name.info.json"
  # the stream at every chunk boundary
  /usr/bin/python3 -c "import json,sys; [print(c['end_byte']) for c in json.load(open(sys.argv[1]))['stream']['chunks']]" "$work/$name.info.json" |
    while read -r bytes; do
      "$tools/tomextract" "$work/stream/$name.tom" --bytes "$bytes" -o "$work/$name-$bytes.obj" > /dev/null
      printf '{"bytes": %s, "tomerr": %s}\n' "$bytes" "$("$tools/tomerr" "$mesh" "$work/$name-$bytes.obj" --json | tr -d '\n')"
    done > "$work/$name.stream.jsonl"
  # the LOD chain's levels and the single level
  for pct in 1 5 25 100; do
    "$tools/tomextract" "$work/plain/$name.tom" --fraction "$(/usr/bin/python3 -c "print($pct / 100)")" --below-floor -o "$work/$name-$pct.glb" > /dev/null
    # a .gltf and its .bin: the geometry and the scene's JSON, the images left as files (as the
    # stream refers to a source's image files)
    mkdir -p "$work/cc-$name-$pct"
    node "$pack" -i "$work/$name-$pct.glb" -o "$work/cc-$name-$pct/level.gltf" -cc > /dev/null
    # its error: the same level quantized as -cc quantizes it (gltfpack's defaults), without the codecs
    node "$pack" -i "$work/$name-$pct.glb" -o "$work/$name-$pct-q.glb" > /dev/null
    printf '{"percent": %s, "bytes": %s, "tomerr": %s}\n' "$pct" "$(cat "$work/cc-$name-$pct"/level.gltf "$work/cc-$name-$pct"/level.bin | wc -c)" \
      "$("$tools/tomerr" "$mesh" "$work/$name-$pct-q.glb" --json | tr -d '\n')"
  done > "$work/$name.chain.jsonl"
done
# decode speed natively and in the browser on the same bytes (one tomstreambench run per mesh)
bash "$root/scripts/bench-web.sh" "${meshes[@]}" > /dev/null
cp "$out/web.jsonl" "$work/web.jsonl"

/usr/bin/python3 - "$work" "$out" "${TOM_PERFORMANCE:-$root/docs/PERFORMANCE.md}" "$root/docs/images/stream.png" "${meshes[@]}" <<'EOF'
import json, os, sys
work, out, doc, plot, meshes = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:]
def mean_of(t):  # the two-sided Metro mean, % of the diagonal (tomerr's `mean` is the larger one-sided mean, in %)
    return t['mean']
result, lines = [], []
web = [json.loads(l) for l in open(f'{work}/web.jsonl')]
native = {w['mesh']: w['native'] for w in web}
lines.append('| mesh | bytes received | boundary of | streamed: triangles | streamed: mean % | LOD chain (1/5/25/100%, gltfpack -cc): level | chain: mean % | stream / chain |')
lines.append('|---|---:|---|---:|---:|---:|---:|---:|')
for mesh in meshes:
    name = os.path.splitext(os.path.basename(mesh))[0]
    stream = [json.loads(l) for l in open(f'{work}/{name}.stream.jsonl')]
    chain = [json.loads(l) for l in open(f'{work}/{name}.chain.jsonl')]
    speed = native[name]
    cumulative, total = [], 0
    for level in chain:
        total += level['bytes']
        cumulative.append((total, level))
    single = chain[-1]
    # both are step functions of the bytes received: compared at every boundary of either, so
    # that the bytes where the chain has a level and the stream not yet (or a coarser one) count
    steps = [(p['bytes'], p) for p in stream]
    def last(seq, b):
        got = [v for (at, v) in seq if at <= b]
        return got[-1] if got else None
    points = []
    for b in sorted({at for (at, _) in steps} | {at for (at, _) in cumulative}):
        p, lv = last(steps, b), last(cumulative, b)
        points.append({'bytes': b, 'boundary': 'stream chunk' if any(at == b for (at, _) in steps) else 'chain level',
                       'triangles': p['tomerr']['simplified_triangles'] if p else 0, 'mean_percent': mean_of(p['tomerr']) if p else None,
                       'chain_level_percent': lv['percent'] if lv else None, 'chain_mean_percent': mean_of(lv['tomerr']) if lv else None,
                       'chain_triangles': lv['tomerr']['simplified_triangles'] if lv else 0,
                       'single_mean_percent': mean_of(single['tomerr']) if b >= single['bytes'] else None})
    at_or_below = all(q['chain_mean_percent'] is None or (q['mean_percent'] is not None and q['mean_percent'] <= q['chain_mean_percent'])
                      for q in points)
    worse = [q['bytes'] for q in points if q['chain_mean_percent'] is not None and (q['mean_percent'] is None or q['mean_percent'] > q['chain_mean_percent'])]
    result.append({'mesh': name, 'stream_bytes': stream[-1]['bytes'], 'first_chunk_bytes': stream[0]['bytes'],
                   'single_cc_bytes': single['bytes'], 'chain_bytes': total, 'chain': [{'percent': c['percent'], 'bytes': c['bytes'],
                   'mean_percent': mean_of(c['tomerr'])} for c in chain], 'points': points, 'at_or_below_chain': at_or_below,
                   'bytes_where_worse': worse, 'speed': speed})
    for q in points:
        stream_err = f"{q['mean_percent']:.4f}" if q['mean_percent'] is not None else 'nothing yet'
        if q['chain_mean_percent'] is None: ratio = 'chain: nothing yet'
        elif q['mean_percent'] is None: ratio = 'stream: nothing yet'
        else: ratio = f"{q['mean_percent'] / q['chain_mean_percent']:.2f}"
        chain_cell = f"{q['chain_level_percent']}%" if q['chain_level_percent'] else '-'
        chain_err = f"{q['chain_mean_percent']:.4f}" if q['chain_mean_percent'] is not None else '-'
        lines.append(f"| {name} | {q['bytes']} | {q['boundary']} | {q['triangles']} | {stream_err} | {chain_cell} | {chain_err} | {ratio} |")
def at_or_below_cell(r):
    if r['at_or_below_chain']: return 'yes'
    w = r['bytes_where_worse']
    # each place: the triangles each side holds there and by how much the stream's error is above
    def place(q):
        if q['mean_percent'] is None: return f"{q['bytes']}: nothing yet"
        held = f"the same {q['triangles']}" if q['triangles'] == q['chain_triangles'] else f"{q['triangles']} triangles against {q['chain_triangles']}"
        above = 100 * (q['mean_percent'] / q['chain_mean_percent'] - 1)
        return f"{q['bytes']}: {held}, {above:.{3 if above < 0.1 else 2}f}% above"
    worse = [q for q in r['points'] if q['bytes'] in w]
    return f"no: {len(w)} of {len(r['points'])} boundaries ({'; '.join(place(q) for q in worse[:3])}{'; ...' if len(w) > 3 else ''})"
summary = ['| mesh | stream bytes | first chunk | gltfpack -cc, one level | stream / one level | LOD chain bytes | streamed error at or below the chain at every byte count | decode Mtri/s | x meshoptimizer |',
           '|---|---:|---:|---:|---:|---:|---|---:|---:|']
for r in result:
    s = r['speed']
    summary.append(f"| {r['mesh']} | {r['stream_bytes']} | {r['first_chunk_bytes']} ({100 * r['first_chunk_bytes'] / r['stream_bytes']:.1f}%) | {r['single_cc_bytes']} | "
                   f"{r['stream_bytes'] / r['single_cc_bytes']:.2f} | {r['chain_bytes']} | {at_or_below_cell(r)} | "
                   f"{s['decode_tris_per_s'] / 1e6:.2f} | {s['speed_over_meshopt']:.3f} |")
speeds = ['| mesh | where | stream MB/s | stream Mtri/s | meshoptimizer Mtri/s (same mesh, its codecs) | stream / meshoptimizer | progressive: ms (images) |',
          '|---|---|---:|---:|---:|---:|---:|']
for w in web:
    chromium = w['browser']['user_agent'].split('Chrome/')[-1].split(' ')[0]
    for where, f in (('native (tomstreambench)', w['native']), (f'browser (chromium {chromium}, wasm)', w['browser'])):
        speeds.append(f"| {w['mesh']} | {where} | {f['decode_mb_per_s']:.2f} | {f['decode_tris_per_s'] / 1e6:.2f} | {f['meshopt_tris_per_s'] / 1e6:.2f} | "
                      f"{f['speed_over_meshopt']:.3f} | {f['progressive_ms']:.1f} ({f['progressive_images']}) |")
intro = ['## Streaming', '',
         '`scripts/bench-stream.sh`: each mesh streamed (`tombuild --stream`: positions 14 bits, normals 8, texture coordinates 12,',
         'as gltfpack\'s defaults) and the two-sided Metro mean (`tomerr`, % of the diagonal) of what the bytes received decode',
         'to (`tomextract --bytes`), against a glTF LOD chain of 1, 5, 25 and 100% of the triangles',
         '(TOM\'s levels, each compressed by the current gltfpack\'s `-cc` into a `.gltf` and `.bin`, images not counted)',
         'fetched coarsest first, and one `-cc` level. The chain\'s errors are measured on its levels quantized as `-cc` quantizes',
         'them (gltfpack\'s defaults, without the codecs): both sides\' errors include their quantization. Both are step',
         'functions of the bytes received, compared at every chunk boundary of the stream and every level boundary of the',
         'chain (a row each). Decode speed:',
         '`tomstreambench` (every byte through `tom::StreamDecoder` and the `.tom` image of the whole, against meshoptimizer\'s',
         'decoders on the same meshes encoded with its codecs), natively and in headless chromium (`scripts/bench-web.sh`: the',
         'wasm runtime against meshoptimizer\'s npm decoder on the very bytes the native run decodes). "Progressive" is what a',
         'viewer spends to show the stream as it arrives: the bytes fed to each chunk boundary and an image (a snapshot) made',
         'after every chunk, all of it, in milliseconds.', '',
         '![Error against bytes received](images/stream.png)', '']
text = '\n'.join(intro + summary + [''] + speeds + [''] + lines) + '\n'
json.dump(result, open(f'{out}/stream.json', 'w'), indent=1)
print(text)
try:
    old = open(doc).read()
except OSError:
    old = ''
start = old.find('## Streaming')
if start >= 0:
    end = old.find('\n## ', start + 1)
    new = old[:start] + text + ('\n' + old[end + 1:] if end >= 0 else '')
else:
    at = old.find('## Walkthrough')
    new = old[:at] + text + '\n' + old[at:] if at >= 0 else old + '\n' + text
open(doc, 'w').write(new)
try:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(result), figsize=(6 * len(result), 4.5), squeeze=False)
    for ax, r in zip(axes[0], result):
        shown = [q for q in r['points'] if q['mean_percent'] is not None]
        ax.step([q['bytes'] / 1e3 for q in shown], [q['mean_percent'] for q in shown], where='post', label='streamed .tom')
        xs, ys, total = [], [], 0
        for c in r['chain']:
            total += c['bytes']
            xs.append(total / 1e3), ys.append(c['mean_percent'])
        ax.step(xs, ys, where='post', label='LOD chain 1/5/25/100%, gltfpack -cc')
        ax.axvline(r['single_cc_bytes'] / 1e3, color='gray', linestyle=':', label='one gltfpack -cc level')
        # the chain's full level is exact (its quantization is not measured): drawn at the floor
        ax.set_ylim(bottom=0.5 * min(q['mean_percent'] for q in shown))
        ax.set_xlabel('kB received'), ax.set_ylabel('two-sided Metro mean, % of diagonal'), ax.set_yscale('log'), ax.set_title(r['mesh'])
        ax.legend()
    fig.tight_layout()
    fig.savefig(plot, dpi=80)
    print(f'plot: {plot}')
except ImportError:
    print('no matplotlib: no plot')
EOF
