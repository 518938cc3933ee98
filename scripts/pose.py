#!/usr/bin/python3
"""Poses a glTF binary's meshes as its source's first animation moves them, for the benchmarks.

usage: scripts/pose.py SOURCE.glb MESH.glb OUT_PREFIX [--poses K]

Writes OUT_PREFIX-<k>.obj for k = 0 .. K-1 (default 8): MESH's triangles in world space at K times
spread evenly over SOURCE's first animation, first and last key included. The joints and nodes
are SOURCE's, animated by SOURCE's channels (linear and step samplers; rotations normalised
lerp), and MESH's nodes and joints are matched to them by name, so that a simplified copy (by
tombuild and tomextract, or by gltfpack, either of which may renumber nodes) is posed exactly as
its source is: what the two differ in is only the mesh. (A joint without a namesake is an
error; a static mesh's node without one, which a tool merging static meshes may make, keeps its
own world matrix in MESH, with a warning.) A skinned primitive's vertices are
sum_k w_k J_k p with J_k = world(joint_k) * inverse_bind_k (WEIGHTS_n normalised to sum 1), its
normals the same with the matrices' inverse transposes; other meshes take their node's world
matrix. Texture coordinates are copied. Exit status 3 when SOURCE has no animation or MESH no
skinned or animated node: nothing moves, the rest pose is all there is.
"""
import json
import struct
import sys

import numpy as np

TYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
WIDTH = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4, 'MAT4': 16}


def fail(message):
    sys.exit('pose.py: ' + message)


class Gltf:
    def __init__(self, path):
        self.path = path
        data = open(path, 'rb').read()
        if data[:4] != b'glTF' or len(data) < 20:
            fail(path + ': not a glTF binary')
        size = struct.unpack_from('<I', data, 12)[0]
        self.json = json.loads(data[20:20 + size])
        at = 20 + size
        self.bin = data[at + 8:at + 8 + struct.unpack_from('<I', data, at)[0]] if at + 8 <= len(data) else b''
        self.nodes = self.json.get('nodes', [])

    def accessor(self, index):
        """An accessor's elements as float64 rows (normalized integers scaled to [0, 1] or [-1, 1])."""
        a = self.json['accessors'][index]
        width, kind = WIDTH[a['type']], np.dtype(TYPES[a['componentType']])
        if 'sparse' in a or 'bufferView' not in a:
            fail('%s: accessor %d is sparse or has no buffer view (not supported here)' % (self.path, index))
        view = self.json['bufferViews'][a['bufferView']]
        offset = view.get('byteOffset', 0) + a.get('byteOffset', 0)
        stride = view.get('byteStride', kind.itemsize * width)
        if a['count'] and offset + stride * (a['count'] - 1) + kind.itemsize * width > len(self.bin):
            fail('%s: accessor %d runs past the binary chunk' % (self.path, index))
        raw = np.frombuffer(self.bin, dtype=np.uint8)[offset:]
        rows = np.lib.stride_tricks.as_strided(raw, shape=(a['count'], kind.itemsize * width), strides=(stride, 1))
        rows = rows.copy().view(kind).reshape(a['count'], width)
        if a.get('normalized'):
            return np.maximum(rows.astype(np.float64) / np.iinfo(kind).max, -1.0)
        return rows.astype(np.float64)

    def parents(self):
        out = {}
        for i, n in enumerate(self.nodes):
            for c in n.get('children', []):
                out[c] = i
        return out


def rotation(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def local_matrix(node, animated):
    """A node's local matrix, its animated paths taking the place of its own."""
    if 'matrix' in node and not animated:
        return np.array(node['matrix'], dtype=np.float64).reshape(4, 4).T
    m = np.eye(4)
    t = animated.get('translation', node.get('translation', [0, 0, 0]))
    r = animated.get('rotation', node.get('rotation', [0, 0, 0, 1]))
    s = animated.get('scale', node.get('scale', [1, 1, 1]))
    m[:3, :3] = rotation(np.asarray(r) / np.linalg.norm(r)) @ np.diag(s)
    m[:3, 3] = t
    return m


class Animation:
    """SOURCE's first animation: its channels' keys, sampled at any time."""

    def __init__(self, gltf):
        self.channels = []
        for ch in gltf.json['animations'][0]['channels']:
            path = ch['target'].get('path')
            if path not in ('translation', 'rotation', 'scale') or 'node' not in ch['target']:
                continue  # (morph weights: the benchmark's skinned assets have none)
            s = gltf.json['animations'][0]['samplers'][ch['sampler']]
            times, values = gltf.accessor(s['input'])[:, 0], gltf.accessor(s['output'])
            if s.get('interpolation', 'LINEAR') == 'CUBICSPLINE':
                values = values[1::3]  # the keys' values, between their tangents (a linear approximation)
            self.channels.append((ch['target']['node'], path, times, values, s.get('interpolation', 'LINEAR') == 'STEP'))
        if not self.channels:
            fail(gltf.path + ': its first animation moves no node')
        self.start = min(c[2][0] for c in self.channels)
        self.end = max(c[2][-1] for c in self.channels)

    def at(self, time):
        out = {}
        for node, path, times, values, step in self.channels:
            k = int(np.searchsorted(times, time, side='right')) - 1
            if k < 0:
                v = values[0]
            elif k >= len(times) - 1:
                v = values[-1]
            else:
                u = 0.0 if step else (time - times[k]) / (times[k + 1] - times[k])
                a, b = values[k], values[k + 1]
                if path == 'rotation' and np.dot(a, b) < 0:
                    b = -b
                v = (1 - u) * a + u * b
            out.setdefault(node, {})[path] = v
        return out


def world_matrices(gltf, animated):
    parent, cache = gltf.parents(), {}

    def world(i):
        if i not in cache:
            m = local_matrix(gltf.nodes[i], animated.get(i, {}))
            cache[i] = world(parent[i]) @ m if i in parent else m
        return cache[i]
    return world


def posed_triangles(source, mesh, world):
    """MESH's triangles posed by SOURCE's node matrices `world`: positions, normals (or None),
    texture coordinates (or None) per corner list, and the triangles."""
    by_name = {n.get('name'): i for i, n in enumerate(source.nodes)}

    def source_node(i):
        name = mesh.nodes[i].get('name')
        if name not in by_name:
            fail('%s: node %d (%r) has no namesake in %s' % (mesh.path, i, name, source.path))
        return by_name[name]
    mesh_world = world_matrices(mesh, {})
    positions, normals, texcoords, triangles = [], [], [], []
    for i, node in enumerate(mesh.nodes):
        if 'mesh' not in node:
            continue
        skin = mesh.json['skins'][node['skin']] if 'skin' in node else None
        if skin:
            inverse_bind = mesh.accessor(skin['inverseBindMatrices']).reshape(-1, 4, 4).transpose(0, 2, 1)
            joints = np.array([world(source_node(j)) @ inverse_bind[k] for k, j in enumerate(skin['joints'])])
        elif node.get('name') in by_name:
            node_matrix = world(by_name[node['name']])
        else:
            print('pose.py: %s: node %d (%r) has no namesake in %s: posed as it stands' % (mesh.path, i, node.get('name'), source.path), file=sys.stderr)
            node_matrix = mesh_world(i)
        for p in mesh.json['meshes'][node['mesh']]['primitives']:
            if p.get('mode', 4) != 4:
                continue
            attributes = p['attributes']
            P = mesh.accessor(attributes['POSITION'])
            N = mesh.accessor(attributes['NORMAL']) if 'NORMAL' in attributes else None
            if skin:
                M = np.zeros((len(P), 4, 4))
                total = np.zeros((len(P), 1))
                for set_ in range(4):
                    if 'JOINTS_%d' % set_ not in attributes:
                        break
                    J = mesh.accessor(attributes['JOINTS_%d' % set_]).astype(int)
                    W = mesh.accessor(attributes['WEIGHTS_%d' % set_])
                    for k in range(J.shape[1]):
                        M += W[:, k, None, None] * joints[J[:, k]]
                        total += W[:, k:k + 1]
                M /= np.where(total > 0, total, 1.0)[:, :, None]
            else:
                M = np.broadcast_to(node_matrix, (len(P), 4, 4))
            base = sum(len(x) for x in positions)
            positions.append(np.einsum('nij,nj->ni', M[:, :3, :3], P) + M[:, :3, 3])
            if N is not None:
                n = np.einsum('nij,nj->ni', np.linalg.inv(M[:, :3, :3]).transpose(0, 2, 1), N)
                normals.append(n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30))
            texcoords.append(mesh.accessor(attributes['TEXCOORD_0']) if 'TEXCOORD_0' in attributes else None)
            index = mesh.accessor(p['indices'])[:, 0].astype(int) if 'indices' in p else np.arange(len(P))
            triangles.append(index.reshape(-1, 3) + base)
    with_normals = len(normals) == len(positions)
    with_uv = all(t is not None for t in texcoords)
    return (np.concatenate(positions), np.concatenate(normals) if with_normals else None,
            np.concatenate(texcoords) if with_uv and texcoords else None, np.concatenate(triangles))


def write_obj(path, positions, normals, texcoords, triangles):
    with open(path, 'w') as f:
        for v in positions:
            f.write('v %.9g %.9g %.9g\n' % tuple(v))
        for t in texcoords if texcoords is not None else []:
            f.write('vt %.9g %.9g\n' % (t[0], 1 - t[1]))  # OBJ's v runs up, glTF's down
        for n in normals if normals is not None else []:
            f.write('vn %.9g %.9g %.9g\n' % tuple(n))
        corner = ('%d/%d/%d' if texcoords is not None else '%d//%d') if normals is not None else ('%d/%d' if texcoords is not None else '%d')
        for t in triangles:
            f.write('f ' + ' '.join(corner % ((i + 1,) * corner.count('%d')) for i in t) + '\n')


def main():
    args = sys.argv[1:]
    poses = 8
    if '--poses' in args:
        at = args.index('--poses')
        poses = int(args[at + 1])
        del args[at:at + 2]
    if len(args) != 3 or poses < 2:
        sys.exit(__doc__)
    source, mesh = Gltf(args[0]), Gltf(args[1])
    if not source.json.get('animations') or not any('skin' in n for n in mesh.nodes):
        sys.exit(3)
    animation = Animation(source)
    for k in range(poses):
        time = animation.start + (animation.end - animation.start) * k / (poses - 1)
        write_obj('%s-%d.obj' % (args[2], k), *posed_triangles(source, mesh, world_matrices(source, animation.at(time))))


if __name__ == '__main__':
    main()
