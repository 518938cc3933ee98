#!/usr/bin/python3
"""One extraction through the C++ API, the C API and the Python package, in the same run.

tomapibench measures C++ and C (rounds alternating); this script then times the Python call
mesh.extract(vertices=n, out=out) the same way (batches of about 2 ms, median over the rounds)
and prints one table, or JSON with --json: per fraction, the median ns per call of each and the
ratios C/C++ and Python - C++ (the binding's cost per call, in microseconds).

Usage: scripts/bench-bindings.py FILE.tom [--rounds R] [--json]
Needs build/tools/tomapibench and build/python (scripts/build.sh)."""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(root, "build", "python"))
import numpy as np  # noqa: E402

import tom  # noqa: E402


def python_ns(mesh, vertices, rounds):
    out = np.empty(3 * mesh.triangle_count, np.uint32)
    mesh.extract(vertices=vertices, out=out)
    start = time.perf_counter()
    mesh.extract(vertices=vertices, out=out)
    batch = max(1, int(2e-3 / max(time.perf_counter() - start, 1e-9)))
    times = []
    for _ in range(rounds):
        start = time.perf_counter_ns()
        for _ in range(batch):
            mesh.extract(vertices=vertices, out=out)
        times.append((time.perf_counter_ns() - start) / batch)
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file")
    parser.add_argument("--rounds", type=int, default=31)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    bench = os.path.join(root, "build", "tools", "tomapibench")
    rows = [json.loads(line) for line in subprocess.run([bench, args.file, "--json", "-r", str(args.rounds)], check=True,
                                                        capture_output=True, text=True).stdout.splitlines()]
    mesh = tom.open(args.file).meshes[0]
    for row in rows:
        row["python_ns"] = python_ns(mesh, row["vertices"], args.rounds)
        row["python_minus_cpp_us"] = (row["python_ns"] - row["cpp_ns"]) / 1000
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
