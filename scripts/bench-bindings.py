#!/usr/bin/python3
"""One extraction through the C++ API, the C API and the Python package, in the same run.

In one process, rounds alternate between the three: a batch of Python calls
mesh.extract(vertices=n, out=out), then the same batch through tom::extract and through
tom_extract_u32 (looped inside the native module), each batch about 2 ms. Per fraction of
bunny00's triangles it prints the median ns per call of each and the ratios C / C++ and
Python - C++ (the binding's cost per call, in microseconds); JSON with --json.
(tomapibench measures C++ against C without Python.)

Usage: scripts/bench-bindings.py FILE.tom [--rounds R] [--json]
Needs build/python (scripts/build.sh)."""
import argparse
import json
import os
import statistics
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(root, "build", "python"))
import numpy as np  # noqa: E402

import tom  # noqa: E402
from tom import _tom  # noqa: E402


def measure(mesh, fraction, rounds):
    n = mesh.vertex_count_for(fraction=fraction)
    out = np.empty(3 * mesh.triangle_count, np.uint32)
    mesh.extract(vertices=n, out=out)
    start = time.perf_counter()
    mesh.extract(vertices=n, out=out)
    batch = max(1, int(2e-3 / max(time.perf_counter() - start, 1e-9)))
    py, cpp, c = [], [], []
    for _ in range(rounds):
        start = time.perf_counter_ns()
        for _ in range(batch):
            mesh.extract(vertices=n, out=out)
        py.append((time.perf_counter_ns() - start) / batch)
        cpp.append(_tom._bench_native(mesh, n, out, batch, "cpp") * 1e9)
        c.append(_tom._bench_native(mesh, n, out, batch, "c") * 1e9)
    row = {"mesh": mesh.name, "fraction": fraction, "vertices": n, "triangles": mesh.active_triangles(n),
           "cpp_ns": statistics.median(cpp), "c_ns": statistics.median(c), "python_ns": statistics.median(py)}
    row["c_over_cpp"] = row["c_ns"] / row["cpp_ns"]
    row["python_minus_cpp_us"] = (row["python_ns"] - row["cpp_ns"]) / 1000
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file")
    parser.add_argument("--rounds", type=int, default=31)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    mesh = tom.open(args.file).meshes[0]
    rows = [measure(mesh, f, args.rounds) for f in (1.0, 0.1, 0.01)]
    if args.json:
        for row in rows:
            print(json.dumps(row))
        return
    print(f"{'fraction':>8} {'vertices':>9} {'triangles':>9} {'C++ ns':>10} {'C ns':>10} {'Python ns':>10} {'C/C++':>7} {'Py-C++ us':>10}")
    for r in rows:
        print(f"{r['fraction']:>8g} {r['vertices']:>9} {r['triangles']:>9} {r['cpp_ns']:>10.0f} {r['c_ns']:>10.0f} {r['python_ns']:>10.0f} "
              f"{r['c_over_cpp']:>7.3f} {r['python_minus_cpp_us']:>10.2f}")


if __name__ == "__main__":
    main()
