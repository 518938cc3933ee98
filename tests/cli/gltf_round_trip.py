"""The round trip source -> .tom -> tomextract --lods 100 of a converted folder keeps, for every
converted glTF, the materials (by name, in order, with their extensions and the images and
samplers of the textures those refer to), the nodes that draw meshes (by name), the bytes
of every material's base-colour image and its sampler, and the scene beyond the meshes: every
node's name, transform, children, skin and camera, the skins' joints and inverse bind matrices,
the animations' channels and keyframe data, the cameras and the scenes. Usage: gltf_round_trip.py OUTDIR (tombuild's output
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
def accessor_bytes(d, binary, folder, i):
    a = d['accessors'][i]
    v = d['bufferViews'][a['bufferView']]
    buf = d['buffers'][v['buffer']]
    data = binary if binary is not None and 'uri' not in buf else (
        base64.b64decode(buf['uri'].split(',', 1)[1]) if buf['uri'].startswith('data:') else open(os.path.join(folder, buf['uri']), 'rb').read())
    size = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4, 'MAT4': 16}[a['type']] * {5121: 1, 5123: 2, 5125: 4, 5126: 4, 5120: 1, 5122: 2}[a['componentType']]
    stride = v.get('byteStride', size)
    start = v.get('byteOffset', 0) + a.get('byteOffset', 0)
    return b''.join(data[start + k * stride:start + k * stride + size] for k in range(a['count']))
def scene_beyond_meshes(d, binary, folder):
    keys = ('name', 'children', 'skin', 'camera', 'matrix', 'translation', 'rotation', 'scale', 'weights', 'extras')
    nodes = [{k: n[k] for k in keys if k in n} | {'has_mesh': 'mesh' in n} for n in d.get('nodes', [])]
    skins = [(s['joints'], accessor_bytes(d, binary, folder, s['inverseBindMatrices']) if 'inverseBindMatrices' in s else None) for s in d.get('skins', [])]
    animations = [([(c['sampler'], c['target']) for c in a['channels']],
                   [(s.get('interpolation', 'LINEAR'), accessor_bytes(d, binary, folder, s['input']), accessor_bytes(d, binary, folder, s['output'])) for s in a['samplers']])
                  for a in d.get('animations', [])]
    samplers = []
    for m in d.get('materials', []):
        t = m.get('pbrMetallicRoughness', {}).get('baseColorTexture')
        tex = d['textures'][t['index']] if t is not None else {}
        samplers.append(d['samplers'][tex['sampler']] if 'sampler' in tex else None)
    return nodes, skins, animations, d.get('cameras', []), d.get('scenes', []), samplers
def material_extensions(d, binary, folder):
    # per material, its extensions (but those converted or baked), each texture they refer to
    # replaced by its image's bytes and sampler
    def resolve(j):
        if isinstance(j, dict):
            if 'index' in j:
                tex = d['textures'][j['index']]
                src = tex.get('source', next(iter(tex.get('extensions', {}).values()), {}).get('source'))
                sampler = d['samplers'][tex['sampler']] if 'sampler' in tex else None
                return {k: resolve(v) for k, v in j.items() if k != 'index'} | {'image': image_bytes(d, binary, src, folder), 'sampler': sampler}
            return {k: resolve(v) for k, v in j.items()}
        if isinstance(j, list):
            return [resolve(v) for v in j]
        return j
    skip = ('KHR_materials_pbrSpecularGlossiness', 'KHR_texture_transform')
    return [{k: resolve(v) for k, v in m.get('extensions', {}).items() if k not in skip} for m in d.get('materials', [])]
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
    assert material_extensions(s, sb, folder) == material_extensions(r, rb, os.path.dirname(rt)), src
    kept, back = scene_beyond_meshes(s, sb, folder), scene_beyond_meshes(r, rb, os.path.dirname(rt))
    for what, a, b in zip(('nodes', 'skins', 'animations', 'cameras', 'scenes', 'samplers'), kept, back):
        assert a == b, (src, what, a, b)
    checked += 1
converted = sum(1 for line in open(os.path.join(out, 'manifest.jsonl')) if json.loads(line).get('status') == 'converted')
print(f"round trip: {checked} assets keep their materials with their extensions, node trees, skins, animations, cameras, images and samplers")
assert checked == converted and checked >= 20, (checked, converted)
