#!/usr/bin/python3
"""Plots of tombuild reports (tombuild --report-json DIR): for every mesh of every report, an
SVG (or PNG) of Metro-style error against triangle count (log-log, mean and max, the fitted k/N lines
and the stored error curve) and an SVG of the substitution-chain length histogram per level.

usage: scripts/plot-report.py REPORT.json [REPORT.json ...] -o OUTDIR [--format svg|png]
"""
import argparse
import json
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")  # no display
import matplotlib.pyplot as plt  # noqa: E402


def safe(name):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_") or "mesh"


def plot_error(mesh, path):
    levels = [l for l in mesh["levels"] if l["triangles"] > 0]
    tris = [l["triangles"] for l in levels]
    mean = [l["error"]["mean"] for l in levels]
    hmax = [l["error"]["hausdorff"] for l in levels]
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    ax.loglog(tris, hmax, "o-", color="tab:red", label="max (Hausdorff)")
    ax.loglog(tris, mean, "s-", color="tab:blue", label="mean")
    lo, hi = min(tris) / 1.5, max(tris) * 1.5
    xs = [lo, hi]
    fit = mesh["fit"]
    # D relative (fraction) = k / N; the plot is in percent
    ax.loglog(xs, [100 * fit["k_max"] / x for x in xs], "--", color="tab:red", alpha=0.6, label="k_max/N, k_max = %.3g" % fit["k_max"])
    ax.loglog(xs, [100 * fit["k_mean"] / x for x in xs], "--", color="tab:blue", alpha=0.6, label="k_mean/N, k_mean = %.3g" % fit["k_mean"])
    # the full-resolution point has no error: leave it off a log plot
    curve = [p for p in (mesh.get("error_curve") or {}).get("points", []) if p["triangles"] > 0 and p["mean"] > 0]
    if curve:
        ax.loglog([p["triangles"] for p in curve], [p["mean"] for p in curve], ":", color="gray", label="stored curve (mean)")
    ax.set_xlabel("triangles")
    ax.set_ylabel("error, % of the bounding-box diagonal")
    ax.set_title("%s: Metro-style error against resolution" % mesh["name"])
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_chains(mesh, path):
    levels = mesh["levels"]
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    width = 0.8 / max(1, len(levels))
    for i, l in enumerate(levels):
        hist = l["chain"]["histogram"]
        total = float(sum(hist)) or 1.0
        xs = [k + i * width for k in range(len(hist))]
        ax.bar(xs, [h / total for h in hist], width=width, label="%g%% (mean %.2f)" % (100 * l["fraction"], l["chain"]["mean_steps"]))
    ax.set_xlabel("substitution steps per corner (last bin: that many or more)")
    ax.set_ylabel("share of corners")
    ax.set_title("%s: substitution-chain lengths per level" % mesh["name"])
    ax.legend(fontsize=8, title="level")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("reports", nargs="+")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--format", choices=["svg", "png"], default="svg")
    args = ap.parse_args()
    os.makedirs(args.output, exist_ok=True)
    written = 0
    failed = 0
    for report in args.reports:
        try:
            with open(report) as f:
                doc = json.load(f)
            stem = safe(os.path.splitext(os.path.basename(report))[0])
            for mesh in doc["meshes"]:
                base = os.path.join(args.output, stem + ("" if len(doc["meshes"]) == 1 else "-" + safe(mesh["name"])))
                plot_error(mesh, base + "-error." + args.format)
                plot_chains(mesh, base + "-chains." + args.format)
                written += 2
        except (OSError, ValueError, KeyError) as e:
            print("error: %s: %s" % (report, e), file=sys.stderr)
            failed += 1
    print("plot-report: %d plots in %s" % (written, args.output))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
