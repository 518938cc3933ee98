"""The Python consumer: maps a .tom file and prints, per mesh, the index count at 10% of its
triangles; with a fraction, prints instead the first mesh's triangles at that fraction as OBJ
faces (1-based), the lines tomextract writes.
Usage: python3 consumer.py FILE.tom [FRACTION]"""
import sys

import numpy as np

import tom


def main(argv):
    if len(argv) not in (2, 3):
        print(f"usage: {argv[0]} FILE.tom [FRACTION]", file=sys.stderr)
        return 2
    try:
        f = tom.open(argv[1])  # mapped in place and validated
    except tom.Error as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    for mesh in f.meshes:
        out = np.empty(3 * mesh.triangle_count, np.uint32)  # once; reused every frame
        indices, n = mesh.extract(fraction=float(argv[2]) if len(argv) == 3 else 0.10, out=out)
        if len(argv) == 3:
            one = indices.astype(np.int64) + 1
            sys.stdout.write("".join(f"f {a}//{a} {b}//{b} {c}//{c}\n" for a, b, c in one.tolist()))
            return 0
        print(f"{mesh.name}: {mesh.vertex_count} vertices, {mesh.triangle_count} triangles; "
              f"at 10%: {n} vertices, {len(indices)} triangles, {indices.size} indices")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
