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


class Piece:
    """One triangle primitive of MESH as posing needs it, read once: its positions, normals (or
    None) and texture coordinates (or None), and `move(world)`, its vertices' matrices (one
    matrix, or one per vertex) at the pose of SOURCE's node matrices `world`."""

    def __init__(self, positions, normals, texcoords, move):
        self.positions, self.normals, self.texcoords, self.move = positions, normals, texcoords, move


def skinning(joints, inverse_bind, influences):
    """The move of a skinned piece: sum_k w_k world(joint_k) inverse_bind_k per vertex, from its
    (joint, normalised weight) columns `influences`."""
    def move(world):
        joint = np.array([world(j) @ b for j, b in zip(joints, inverse_bind)])
        return sum(w[:, None, None] * joint[j] for j, w in influences)
    return move


def read_pieces(source, mesh):
    """MESH's triangle primitives (Piece), and their triangles numbered across them."""
    by_name = {n.get('name'): i for i, n in enumerate(source.nodes)}

    def source_node(i):
        name = mesh.nodes[i].get('name')
        if name not in by_name:
            fail('%s: node %d (%r) has no namesake in %s' % (mesh.path, i, name, source.path))
        return by_name[name]
    mesh_world = world_matrices(mesh, {})
    pieces, triangles, base = [], [], 0
    for i, node in enumerate(mesh.nodes):
        if 'mesh' not in node:
            continue
        skin = mesh.json['skins'][node['skin']] if 'skin' in node else None
        if skin:
            joints = [source_node(j) for j in skin['joints']]
            inverse_bind = mesh.accessor(skin['inverseBindMatrices']).reshape(-1, 4, 4).transpose(0, 2, 1)
        elif node.get('name') in by_name:
            move = lambda world, n=by_name[node['name']]: world(n)
        else:
            print('pose.py: %s: node %d (%r) has no namesake in %s: posed as it stands' % (mesh.path, i, node.get('name'), source.path), file=sys.stderr)
            move = lambda world, m=mesh_world(i): m
        for p in mesh.json['meshes'][node['mesh']]['primitives']:
            if p.get('mode', 4) != 4:
                continue
            attributes = p['attributes']
            P = mesh.accessor(attributes['POSITION'])
            if skin:
                influences = []
                for set_ in range(4):
                    if 'JOINTS_%d' % set_ not in attributes:
                        break
                    J = mesh.accessor(attributes['JOINTS_%d' % set_]).astype(int)
                    W = mesh.accessor(attributes['WEIGHTS_%d' % set_])
                    influences += [(J[:, k], W[:, k]) for k in range(J.shape[1])]
                total = sum(w for _, w in influences)
                total = np.where(total > 0, total, 1.0)
                move = skinning(joints, inverse_bind, [(j, w / total) for j, w in influences])
            pieces.append(Piece(P, mesh.accessor(attributes['NORMAL']) if 'NORMAL' in attributes else None,
                                mesh.accessor(attributes['TEXCOORD_0']) if 'TEXCOORD_0' in attributes else None, move))
            index = mesh.accessor(p['indices'])[:, 0].astype(int) if 'indices' in p else np.arange(len(P))
            triangles.append(index.reshape(-1, 3) + base)
            base += len(P)
    return pieces, np.concatenate(triangles)


def posed(pieces, world):
    """The pieces' positions and normals (or None) at SOURCE's node matrices `world`."""
    positions, normals = [], []
    for piece in pieces:
        M = np.broadcast_to(piece.move(world), (len(piece.positions), 4, 4))
        positions.append(np.einsum('nij,nj->ni', M[:, :3, :3], piece.positions) + M[:, :3, 3])
        if piece.normals is not None:
            n = np.einsum('nij,nj->ni', np.linalg.inv(M[:, :3, :3]).transpose(0, 2, 1), piece.normals)
            normals.append(n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30))
    return np.concatenate(positions), np.concatenate(normals) if len(normals) == len(pieces) else None


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
    pieces, triangles = read_pieces(source, mesh)
    texcoords = np.concatenate([p.texcoords for p in pieces]) if all(p.texcoords is not None for p in pieces) else None
    for k in range(poses):
        time = animation.start + (animation.end - animation.start) * k / (poses - 1)
        positions, normals = posed(pieces, world_matrices(source, animation.at(time)))
        write_obj('%s-%d.obj' % (args[2], k), positions, normals, texcoords, triangles)


if __name__ == '__main__':
    main()
