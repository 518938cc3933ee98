"""A Python engine's time-critical loop on tom.tcr: it calibrates its renderer (numpy
transforming every index's vertex, timed by time.perf_counter), then draws 16 copies of a mesh
under the exact selector and the frame governor, each frame planned, extracted, drawn and timed.
Prints the calibrated per-triangle cost, how the budget held and the share of triangles drawn.
Usage: python3 governed.py FILE.tom [BUDGET_MS]"""
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one thread draws: BLAS threads would spin between draws
import numpy as np  # noqa: E402 (after the thread count)

import tom  # noqa: E402


class NumpyRenderer:
    """Draws a level by moving every index's vertex through the object's matrix: the engine's
    renderer, and calibration's (time_frame)."""
    width, height = 1280, 720

    def __init__(self, positions, max_indices):
        self.points = np.c_[positions, np.ones(len(positions), np.float32)]
        self.gathered = np.empty((max_indices, 4), np.float32)  # once: a draw allocates nothing
        self.moved = np.empty((max_indices, 4), np.float32)
        self.checksum = 0.0

    def draw(self, indices, model):
        flat = indices.reshape(-1)
        gathered, moved = self.gathered[: len(flat)], self.moved[: len(flat)]
        np.take(self.points, flat, axis=0, out=gathered)
        np.matmul(gathered, model.T, out=moved)
        self.checksum += float(moved[:, 2].sum())

    def time_frame(self, camera, draws, way):
        if way != "smooth":
            return -1.0  # one way only: the others stay uncalibrated
        start = time.perf_counter()
        for d in draws:
            self.draw(d["indices"], d["model"])
        return 1000.0 * (time.perf_counter() - start)


def main(argv):
    if len(argv) not in (2, 3):
        print(f"usage: {argv[0]} FILE.tom [BUDGET_MS]", file=sys.stderr)
        return 2
    f = tom.open(argv[1])
    mesh = f.meshes[0]
    renderer = NumpyRenderer(mesh.positions, 3 * mesh.triangle_count)
    model = tom.tcr.calibrate(renderer, [mesh])
    rt = tom.tcr.Runtime(model, "exact")
    transforms = []
    for i in range(16):  # a 4 x 4 grid, 3 to 5 units ahead
        t = np.eye(4, dtype=np.float32)
        t[0, 3], t[1, 3], t[2, 3] = 0.6 * (i % 4) - 0.9, 0.6 * (i // 4) - 0.9, -3.0 - (i % 3)
        transforms.append(t)
        rt.add_object(mesh, t)
    budget_ms = float(argv[2]) if len(argv) == 3 else 3.0
    governor = tom.tcr.FrameGovernor(rt, model, budget_ms=budget_ms)
    view = tom.tcr.look_at([0, 0, 0], [0, 0, -1], [0, 1, 0])
    projection = tom.tcr.perspective(1.2, 16 / 9, 0.1, 100.0)
    frames, triangles = [], []
    for frame in range(150):
        warming_up, reserve_ms = governor.warming_up, governor.planning_reserve_ms
        report = governor.plan_frame(view, projection, renderer.width, renderer.height)
        extract_ms = render_ms = 0.0
        for i in range(len(rt)):  # each drawn object's level, extracted and drawn
            if not rt.object(i)["drawn"]:
                continue
            start = time.perf_counter()
            indices, n = rt.indices(i)
            drawn = time.perf_counter()
            renderer.draw(indices, transforms[i])
            extract_ms += 1000.0 * (drawn - start)
            render_ms += 1000.0 * (time.perf_counter() - drawn)
        governor.frame_done(extract_ms, render_ms)
        if not warming_up and frame >= 30:  # the correction settles
            frames.append(reserve_ms + extract_ms + render_ms)
            triangles.append(report["triangles"])
    frames = np.array(frames)
    print(f"calibrated {model.t_tri_ms + 0.5 * model.t_vert_ms:.3g} ms a triangle; 16 objects, {len(frames)} frames at {budget_ms:.1f} ms: "
          f"{int((frames > 1.1 * budget_ms).sum())} over 1.1x the budget, mean {frames.mean():.2f} ms, "
          f"{100 * np.mean(triangles) / (16 * mesh.triangle_count):.0f}% of the triangles (checksum {renderer.checksum:.0f})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
