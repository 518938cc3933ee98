"""The round trip source -> .tom -> tomextract --lods 100 of a converted folder keeps, for every
converted glTF, the materials (by name, in order), the nodes that draw meshes (by name) and the
bytes of every material's base-colour image. Usage: gltf_round_trip.py OUTDIR (tombuild's output
folder, with NAME.glb beside each NAME.tom)."""
import base64
import json
import os
import struct
import sys

out = sys.argv[1]
def load(path):
    b = open(path, 'rb').read()
    if path.endswith('.glb'):
        n = struct.unpack('<I', b[12:16])[0]; d = json.loads(b[20:20 + n]); binary = b[28 + n:]
    else:
        d = json.loads(b); binary = None
    return d, binary
def image_bytes(d, binary, i, folder):
    im = d['images'][i]
    if 'bufferView' in im:
        v = d['bufferViews'][im['bufferView']]; o = v.get('byteOffset', 0)
        return binary[o:o + v['byteLength']]
    if im['uri'].startswith('data:'):
        return base64.b64decode(im['uri'].split(',', 1)[1])
    return open(os.path.join(folder, im['uri']), 'rb').read()
def mesh_nodes(d):
    scene = d['scenes'][d.get('scene', 0)]
    names, stack = [], list(scene['nodes'])
    while stack:
        n = d['nodes'][stack.pop()]
        if 'mesh' in n: names.append(n.get('name', ''))
        stack += n.get('children', [])
    return sorted(names)
def base_images(d, binary, folder):
    out = []
    for m in d.get('materials', []):
        t = m.get('pbrMetallicRoughness', {}).get('baseColorTexture')
        if t is None: out.append(None); continue
        tex = d['textures'][t['index']]
        src = tex.get('source', next(iter(tex.get('extensions', {}).values()), {}).get('source'))
        out.append(image_bytes(d, binary, src, folder) if src is not None else None)
    return out
checked = 0
for line in open(os.path.join(out, 'manifest.jsonl')):
    rec = json.loads(line)
    if rec.get('status') != 'converted': continue
    src = rec['input']; rt = rec['output'][:-4] + '.glb'
    s, sb = load(src); r, rb = load(rt)
    folder = os.path.dirname(src)
    assert [m.get('name', '') for m in s.get('materials', [])] == [m['name'] for m in r.get('materials', [])], src
    assert mesh_nodes(s) == mesh_nodes(r), (src, mesh_nodes(s), mesh_nodes(r))
    assert base_images(s, sb, folder) == base_images(r, rb, os.path.dirname(rt)), src
    checked += 1
converted = sum(1 for line in open(os.path.join(out, 'manifest.jsonl')) if json.loads(line).get('status') == 'converted')
print(f"round trip: {checked} assets keep their materials, mesh nodes and base-colour images")
assert checked == converted and checked >= 20, (checked, converted)
