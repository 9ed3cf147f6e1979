#!/usr/bin/env python3
"""Plots of the CSV files written by `make bench-tables` (bench/bench_tables.c).

    python3 tools/plot.py [--tables build/bench-tables/tables] [--out build/bench-tables/plots]
(any python3 with matplotlib, e.g. build/venv/bin/python).

The defaults plot the latest `make bench-tables` run under build/ and never touch tracked
files; after `make bench-tables-accept`, redraw the committed plots with
    python3 tools/plot.py --tables bench/tables --out bench/plots

Writes SVG and PNG files:
  accuracy_vs_time_<scene>  image error vs frame time, one curve per method
  wu2020_fig8               SH lighting time vs number of lights
  wu2020_fig9               grid resolution vs time and image error
  hvl2022_table1            HVL gathering time vs HVL count, per band count
A CSV that does not exist (its section was not run) is skipped with a note.
"""
import argparse
import csv
import os
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_csv(path):
    if not os.path.exists(path):
        print(f"plot.py: {path} not found, skipped", file=sys.stderr)
        return None
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def save(fig, out, name):
    for ext in ("svg", "png"):
        fig.savefig(os.path.join(out, f"{name}.{ext}"), dpi=130, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {out}/{name}.svg and .png")


def accuracy_vs_time(rows, out):
    scenes = OrderedDict()
    for r in rows:
        scenes.setdefault(r["scene"], OrderedDict()).setdefault(r["method"], []).append(r)
    for scene, methods in scenes.items():
        fig, ax = plt.subplots(figsize=(7.5, 5))
        for method, pts in methods.items():
            x = [float(p["frame_ms"]) for p in pts]
            y = [max(float(p["rel_mae"]), 1e-9) for p in pts]
            ax.plot(x, y, marker="o", markersize=3.5, label=method)
            ax.annotate(pts[0]["parameter"].split(",")[0], (x[0], y[0]), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")
            ax.annotate(pts[-1]["parameter"].split(",")[0], (x[-1], y[-1]), fontsize=6, xytext=(3, -8),
                        textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("frame time (ms)")
        ax.set_ylabel("image MAE / mean radiance")
        ax.set_title(f"What accuracy costs in time: {scene}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        save(fig, out, f"accuracy_vs_time_{scene}")


def wu_fig8(rows, out):
    n = [int(r["lights"]) for r in rows]
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for key, label in (("pervertex_double_ms", "per-vertex analytic (double)"),
                       ("pervertex_float_ms", "per-vertex analytic (float SIMD)"),
                       ("grid_total_ms", "grid 8^3: fill + Hermite"),
                       ("grid_fill_ms", "grid fill (coefficients + gradients)"),
                       ("grid_interp_ms", "Hermite interpolation")):
        ax.plot(n, [float(r[key]) for r in rows], marker="o", markersize=3.5, label=label)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("number of lights")
    ax.set_ylabel("time (ms)")
    ax.set_title("Wu 2020 Fig. 8: SH lighting at all vertices")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, out, "wu2020_fig8")


def wu_fig9(rows, out):
    res = [int(r["res"]) for r in rows]
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.plot(res, [float(r["frame_ms"]) for r in rows], marker="o", color="tab:blue", label="frame time")
    ax.plot(res, [float(r["fill_ms"]) for r in rows], marker="s", color="tab:cyan", label="grid fill")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("grid resolution per axis")
    ax.set_ylabel("time (ms)")
    ax2 = ax.twinx()
    ax2.plot(res, [float(r["rel_mae"]) for r in rows], marker="^", color="tab:red", label="image MAE / mean")
    ax2.set_yscale("log")
    ax2.set_ylabel("image MAE / mean radiance")
    lines = ax.get_legend_handles_labels()
    lines2 = ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], fontsize=8, loc="upper center")
    ax.set_title("Wu 2020 Fig. 9: grid resolution vs time and error")
    ax.grid(True, which="both", alpha=0.3)
    save(fig, out, "wu2020_fig9")


def hvl_table1(rows, out):
    bands = OrderedDict()
    for r in rows:
        bands.setdefault(r["bands"], []).append(r)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for b, pts in bands.items():
        ax.plot([int(p["hvls"]) for p in pts], [float(p["ms"]) for p in pts], marker="o", label=f"{b} bands (ours)")
        ax.plot([int(p["hvls_requested"]) for p in pts], [float(p["paper_ms"]) for p in pts], linestyle="--",
                marker="x", label=f"{b} bands (paper, GPU)")
    ax.set_xlabel("HVLs")
    ax.set_ylabel("gathering time (ms)")
    ax.set_title("HVL Table 1: gathering time")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    save(fig, out, "hvl2022_table1")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tables", default="build/bench-tables/tables", help="directory of the CSV files")
    ap.add_argument("--out", default="build/bench-tables/plots", help="output directory")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    for name, fn in (("accuracy_vs_time.csv", accuracy_vs_time), ("wu2020_fig8.csv", wu_fig8),
                     ("wu2020_fig9.csv", wu_fig9), ("hvl2022_table1.csv", hvl_table1)):
        rows = read_csv(os.path.join(args.tables, name))
        if rows:
            fn(rows, args.out)


if __name__ == "__main__":
    main()
