#!/usr/bin/python3
"""Plots of a tcrwalk run (tcrwalk --out DIR): frame time against frame for every selector with
the budget, visible and drawn triangles against frame, and (after --quality-every) each
selector's SSIM against full detail along the path.

usage: scripts/plot-walk.py DIR [--budget-ms B] [--format svg|png]
"""
import argparse
import csv
import glob
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ORDER = ["none", "static", "stress", "greedy", "barrier", "exact"]


def load(directory):
    runs = {}
    for path in glob.glob(os.path.join(directory, "frames-*.csv")):
        name = os.path.basename(path)[len("frames-"):-len(".csv")]
        with open(path) as f:
            runs[name] = list(csv.DictReader(f))
    return {k: runs[k] for k in sorted(runs, key=lambda n: ORDER.index(n) if n in ORDER else 99)}


def save(fig, ax, ylabel, title, legend_columns, path):
    """Labels a plot against frame, writes it to path and closes it."""
    ax.set_xlabel("frame")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8, ncol=legend_columns)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("directory")
    ap.add_argument("--budget-ms", type=float)
    ap.add_argument("--format", choices=["svg", "png"], default="png")
    args = ap.parse_args()
    runs = load(args.directory)
    if not runs:
        print("error: no frames-*.csv in %s" % args.directory, file=sys.stderr)
        return 1
    budget = args.budget_ms
    summary = os.path.join(args.directory, "summary.json")
    if budget is None and os.path.exists(summary):
        with open(summary) as f:
            budget = json.load(f)[0]["budget_ms"]
    fig, ax = plt.subplots(figsize=(9, 4.8))
    for name, rows in runs.items():
        ax.plot([int(r["frame"]) for r in rows], [float(r["measured_ms"]) for r in rows], label=name, linewidth=1.2 if name != "none" else 0.8)
    if budget:
        ax.axhline(budget, color="black", linestyle="--", linewidth=1, label="budget")
        ax.axhline(1.1 * budget, color="gray", linestyle=":", linewidth=1, label="1.1 x budget")
        ax.set_ylim(0, 3 * budget)
    save(fig, ax, "frame time (ms)", "Frame time along the path (A: crowd close up, B: few far objects, C: spin)", 4,
         os.path.join(args.directory, "frame-times." + args.format))
    fig, ax = plt.subplots(figsize=(9, 4.8))
    first = next(iter(runs.values()))
    ax.semilogy([int(r["frame"]) for r in first], [max(1, int(r["visible_triangles"])) for r in first], color="black", label="visible (full detail)")
    for name, rows in runs.items():
        if name == "none":
            continue
        ax.semilogy([int(r["frame"]) for r in rows], [max(1, int(r["drawn_triangles"])) for r in rows], label="drawn: " + name)
    save(fig, ax, "triangles", "Visible and drawn triangles along the path", 3,
         os.path.join(args.directory, "triangles." + args.format))
    written = ["frame-times", "triangles"]
    quality = os.path.join(args.directory, "quality.csv")
    if os.path.exists(quality):
        with open(quality) as f:
            scores = list(csv.DictReader(f))
        fig, ax = plt.subplots(figsize=(9, 4.8))
        for name in runs:
            rows = sorted((int(r["frame"]), float(r["ssim"])) for r in scores if r["selector"] == name)
            if rows and name != "none":
                ax.plot([f for f, _ in rows], [q for _, q in rows], marker="o", markersize=3, label=name)
        save(fig, ax, "SSIM against full detail", "The image each selector draws, against the same view at full detail", 3,
             os.path.join(args.directory, "quality." + args.format))
        written.append("quality")
    print("plot-walk: %s in %s" % (", ".join(w + "." + args.format for w in written), args.directory))
    return 0


if __name__ == "__main__":
    sys.exit(main())
