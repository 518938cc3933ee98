#!/usr/bin/python3
"""Plots tcrmodel's CSV (tcrmodel --csv FILE): each representation's link load over distance,
where it meets the distortion bound (Pasman & Jansen's Figure 11), and the polygons each needs.
Usage: scripts/plot-model.py MODEL.csv -o OUT.png"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("-o", "--output", required=True)
    args = ap.parse_args()
    series = {}
    with open(args.csv, newline="") as f:
        for row in csv.DictReader(f):
            s = series.setdefault(row["method"], {"d": [], "link": [], "polygons": []})
            ok = row["feasible"] == "1"
            s["d"].append(float(row["distance_m"]))
            s["link"].append(float(row["link_bytes_per_s"]) / 1e3 if ok else float("nan"))
            s["polygons"].append(float(row["polygons"]) if ok else float("nan"))
    if not series:
        sys.exit(f"plot-model: {args.csv} has no rows")
    fig, (load, polys) = plt.subplots(1, 2, figsize=(12, 4.5))
    for name, s in series.items():
        load.plot(s["d"], s["link"], label=name.replace("_", " "))
        if name not in ("simple_imposter", "image_with_depth", "layered_depth_image"):
            polys.plot(s["d"], s["polygons"], label=name.replace("_", " "))
    for ax, title, unit in ((load, "link load where the bound is met", "kB/s"), (polys, "polygons needed", "polygons")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("distance to the object (m)")
        ax.set_ylabel(unit)
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    load.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.output, dpi=110)
    print(f"plot-model: {args.output}")


if __name__ == "__main__":
    main()
