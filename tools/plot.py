#!/usr/bin/env python3
"""Plots of the CSV files written by `make bench-tables` (bench/bench_tables.c).

    build/venv-plot/bin/python tools/plot.py [--tables build/bench-tables/tables] [--out build/bench-tables/plots]

'make plots' runs it with these defaults (after 'make venv-plot': numpy and matplotlib only,
tools/requirements-plot.txt): it draws the latest `make bench-tables` run under build/ and never
touches tracked files; `make bench-tables-accept` then copies a complete run's tables and
plots over bench/tables/ and bench/plots/.

Writes SVG and PNG files:
  accuracy_vs_time_<scene>  image error vs frame time, every method at every lmax, Pareto front
  wu2020_fig8               SH lighting time vs number of lights
  wu2020_fig9               grid resolution vs time and image error
  hvl2022_table1            HVL gathering time vs HVL count, per band count
  agrid_<scene>             adaptive vs uniform grids: error vs nodes and vs fill time
                            (bench_agrid.csv: build/bench/bench_agrid -d <tables dir>)
  agrid_image_<scene>       the same on rendered images (bench_agrid_image.csv, same run)
  wu2020_fig4, wu2020_fig6  one coefficient along a line; gradient images vs finite differences
  annen2004_fig8            error of one extrapolated sample vs distance
  wang2018_fig4, wang2018_fig5, wu2020_fig7, wu2020_fig12, hvl2022_table2
                            image panels written by bench_tables (<out>/panels/*.png, from the
                            same run) in a grid, with the central scanline where its CSV exists
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


def save(fig, out, name, exts=("svg", "png")):
    for ext in exts:
        fig.savefig(os.path.join(out, f"{name}.{ext}"), dpi=130, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {out}/{name}: {', '.join(exts)}")


def pareto(points):
    """The points no other point beats in both time and error, by increasing time."""
    front, best = [], float("inf")
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


SWEEP_STYLE = {  # family -> colour, marker
    "per-vertex float": ("tab:blue", "o"),
    "per-vertex double": ("tab:cyan", "s"),
    "grid 8^3 Hermite": ("tab:orange", "^"),
    "grid 16^3 Hermite": ("tab:red", "v"),
    "grid 32^3 Hermite": ("tab:brown", "D"),
    "grid 16^3 trilinear": ("tab:pink", "<"),
    "adaptive grid, 4096 nodes": ("tab:purple", "P"),
}
MC_COLOURS = ("tab:olive", "tab:green", "darkgreen", "black")


def accuracy_vs_time(rows, out):
    """One plot per scene: every method at every lmax (numbers beside the points), grids also with
    static lights (hollow markers: frame without the fill), the Pareto front of the full frames
    ringed and listed beside the axes."""
    scenes = OrderedDict()
    for r in rows:
        scenes.setdefault(r["scene"], OrderedDict()).setdefault(r["method"], []).append(r)
    for scene, methods in scenes.items():
        fig, ax = plt.subplots(figsize=(10.5, 6.5))
        allpts, nmc, floors = [], 0, {}
        for method, pts in methods.items():
            pts = sorted(pts, key=lambda p: int(p["lmax"]))
            if method in SWEEP_STYLE:
                colour, marker = SWEEP_STYLE[method]
            else:
                colour, marker = MC_COLOURS[min(nmc, len(MC_COLOURS) - 1)], "x"
                nmc += 1
            x = [float(p["frame_ms"]) for p in pts]
            y = [max(float(p["rel_mae"]), 1e-9) for p in pts]
            allpts += [(xi, yi, method, p) for xi, yi, p in zip(x, y, pts)]
            ax.plot(x, y, marker=marker, markersize=4.5, color=colour, linewidth=1, label=method)
            for p, xi, yi in zip(pts, x, y):
                ax.annotate(p["lmax"], (xi, yi), fontsize=6, color=colour, xytext=(3, 2), textcoords="offset points")
            if method == "per-vertex float":
                floors = {p["lmax"]: yi for p, yi in zip(pts, y)}
            if (method.startswith("grid") and "Hermite" in method) or method.startswith("adaptive grid"):
                xs = [float(p["frame_ms"]) - float(p["fill_ms"]) for p in pts]
                ax.plot(xs, y, marker=marker, markersize=4.5, color=colour, linewidth=0.8, linestyle=":", alpha=0.6,
                        markerfacecolor="none", label=f"{method}, static lights (no fill)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        for yi in floors.values():  # the truncation error of each lmax: every method's floor there
            ax.axhline(yi, color="grey", linestyle=(0, (1, 4)), linewidth=0.7, zorder=0)
        front = pareto(allpts)
        ax.plot([p[0] for p in front], [p[1] for p in front], color="black", linewidth=6, alpha=0.15,
                solid_capstyle="round", zorder=0, label="Pareto front (no point faster and more accurate)")
        ax.scatter([p[0] for p in front], [p[1] for p in front], s=80, facecolors="none", edgecolors="black",
                   linewidths=0.8, zorder=3)
        text = "Pareto front, lights moving\n(fastest first):\n" + "\n".join(
            f"{p[2]}, lmax {p[3]['lmax']}: {p[0]:.3g} ms, {p[1]:.2e}" for p in front)
        ax.text(1.13, 0.0, text, transform=ax.transAxes, fontsize=7, va="bottom", ha="left", family="monospace")
        ax.set_xlabel("frame time (ms): lighting (+ grid fill) + shading + raster + resolve")
        ax.set_ylabel("image MAE / mean radiance")
        ax.set_title(f"What accuracy costs in time: {scene}\n"
                     "(numbers beside the points: lmax; hollow markers: grids with static lights, filled once)",
                     fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.12, 1.0))
        right = ax.twinx()  # the floors named on the right axis, clear of the points
        right.set_yscale("log")
        right.set_ylim(ax.get_ylim())
        right.set_yticks(list(floors.values()), [f"lmax {k} floor" for k in floors], fontsize=6.5, color="grey")
        right.minorticks_off()
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


def wu_fig4(rows, out, tables):
    """The coefficient along the line, the three interpolants and the 10 samples with their slopes."""
    x = [float(r["x"]) for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for key, label, style in (("reference", "reference (per point)", dict(color="tab:blue", linewidth=2.5, alpha=0.5)),
                              ("trilinear", "trilinear", dict(color="tab:red")),
                              ("taylor_b2", "Taylor (b = 2)", dict(color="tab:cyan")),
                              ("hermite", "Hermite", dict(color="black", linestyle="--"))):
        ax.plot(x, [float(r[key]) for r in rows], label=label, linewidth=style.pop("linewidth", 1.2), **style)
    samples = read_csv(os.path.join(tables, "wu2020_fig4_samples.csv")) or []
    if samples:
        sx = [float(p["x"]) for p in samples]
        sv = [float(p["value"]) for p in samples]
        ax.plot(sx, sv, "o", color="tab:orange", label="samples (value + gradient)")
        half = 0.12
        for xi, vi, di in zip(sx, sv, (float(p["ddx"]) for p in samples)):
            ax.plot([xi - half, xi + half], [vi - di * half, vi + di * half], color="tab:orange", linewidth=1)
    ax.set_xlabel("x (y = 0.3, z = 0)")
    ax.set_ylabel("SH coefficient (7, 2)")
    ax.set_title("Wu 2020 Fig. 4: interpolating one coefficient from 10 samples", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    save(fig, out, "wu2020_fig4")


def wu_fig6(rows, out):
    """d/dx of two coefficients over the region, analytic and central differences, and their difference."""
    n = max(int(r["i"]) for r in rows) + 1
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.4))
    fig.subplots_adjust(wspace=0.5, hspace=0.3)
    for q, (key, lm) in enumerate((("6_m3", "(6,-3)"), ("7_2", "(7,2)"))):
        grids = {k: [[0.0] * n for _ in range(n)] for k in ("analytic", "fd")}
        for r in rows:
            i, j = int(r["i"]), int(r["j"])
            grids["analytic"][n - 1 - j][i] = float(r[f"analytic_{key}"])
            grids["fd"][n - 1 - j][i] = float(r[f"fd_{key}"])
        lim = max(abs(v) for row in grids["analytic"] for v in row)
        diff = [[a - b for a, b in zip(ra, rb)] for ra, rb in zip(grids["analytic"], grids["fd"])]
        for c, (img, title, vmax) in enumerate(((grids["analytic"], f"d/dx {lm}, analytic", lim),
                                                (grids["fd"], f"d/dx {lm}, central differences", lim),
                                                (diff, "analytic - FD", max(abs(v) for row in diff for v in row)))):
            ax = axes[q][c]
            im = ax.imshow(img, cmap="RdBu_r", vmin=-vmax, vmax=vmax, extent=(3, 6, 3, 6))
            ax.set_title(title, fontsize=8)
            ax.tick_params(labelsize=6)
            fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04).ax.tick_params(labelsize=6)
    fig.suptitle("Wu 2020 Fig. 6: SH gradients, light (-5,-5,1)-(5,5,1), region (3,3,0)-(6,6,0)", fontsize=10)
    save(fig, out, "wu2020_fig6", exts=("png",))


def annen_fig8(rows, out):
    """The paper's two curves (red: the blue emitter blocks, green: blue emitter removed), each
    extrapolated with the gradient (solid) and by the sample alone (dashed); grey: all three
    emitters with no occlusion between them (what the library's light sets compute)."""
    d = [float(r["distance"]) for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for key, color, label in (("blocker", "tab:red", "blue emitter blocks (occlusion changes)"),
                              ("no_blue", "tab:green", "blue emitter removed"),
                              ("", "tab:gray", "all three, no occlusion between emitters")):
        k = "_" + key if key else ""
        ax.plot(d, [float(r["rms_error_gradient" + k]) for r in rows], marker="o", markersize=3, color=color,
                label=label + ": sample + gradient")
        ax.plot(d, [float(r["rms_error_sample" + k]) for r in rows], linestyle="--", color=color,
                label=label + ": sample alone")
    ax.set_xlabel("distance from the sample (scene units; the tooth is 1.2 wide, 1.56 tall)")
    ax.set_ylabel("RMS error of incident radiance (red channel)")
    ax.set_title("Annen 2004 Fig. 8: one extrapolated sample, tooth", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    save(fig, out, "annen2004_fig8")


def hvl_table1(rows, out):
    """Ours (CPU) and the paper's (GPU) times on separate axes, then both normalized to their
    own 3-band time at the fewest HVLs: only the shape (growth with HVLs and bands) compares."""
    bands = OrderedDict()
    for r in rows:
        bands.setdefault(r["bands"], []).append(r)
    fig, (ax_ours, ax_paper, ax_norm) = plt.subplots(1, 3, figsize=(13, 4.2))
    base = OrderedDict()
    for i, (b, pts) in enumerate(bands.items()):
        base.setdefault("ours", float(pts[0]["ms"]))
        base.setdefault("paper", float(pts[0]["paper_ms"]))
        n_ours = [int(p["hvls"]) for p in pts]
        n_paper = [int(p["hvls_requested"]) for p in pts]
        ours = [float(p["ms"]) for p in pts]
        paper = [float(p["paper_ms"]) for p in pts]
        ax_ours.plot(n_ours, ours, marker="o", color=f"C{i}", label=f"{b} bands")
        ax_paper.plot(n_paper, paper, marker="x", linestyle="--", color=f"C{i}", label=f"{b} bands")
        ax_norm.plot(n_ours, [v / base["ours"] for v in ours], marker="o", color=f"C{i}", label=f"{b} bands, ours")
        ax_norm.plot(n_paper, [v / base["paper"] for v in paper], marker="x", linestyle="--", color=f"C{i}",
                     label=f"{b} bands, paper")
    ax_ours.set_title("ours: CPU, 2 threads", fontsize=9)
    ax_ours.set_ylabel("gathering time (ms)")
    ax_paper.set_title("paper: RTX 2080 GPU (its Table 1)", fontsize=9)
    ax_paper.set_ylabel("gathering time (ms)")
    ax_norm.set_title("both / own 3-band time at the fewest HVLs", fontsize=9)
    ax_norm.set_ylabel("relative time")
    for ax in (ax_ours, ax_paper, ax_norm):
        ax.set_xlabel("HVLs")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6.5, ncol=2 if ax is ax_norm else 1)
    fig.suptitle("HVL Table 1: indirect-light gathering time (different hardware: compare shapes, not ms)",
                 fontsize=10)
    save(fig, out, "hvl2022_table1")


# Figures composed of the panels bench_tables writes: (panel file suffixes, titles) per row.
PANEL_FIGURES = {
    "wang2018_fig4": ("Wang 2018 Fig. 4: analytic vs Monte Carlo projection (lmax 8)",
                      [[("analytic", "analytic"), ("monte-carlo", "stratified Monte Carlo, ~16384 samples"),
                        ("error", "10 x |difference|")]], "wang2018_fig4.csv"),
    "wang2018_fig5": ("Wang 2018 Fig. 5: shadows at SH orders 2, 4, 6, 8",
                      [[("lmax2", "lmax 2"), ("lmax4", "lmax 4"), ("lmax6", "lmax 6"), ("lmax8", "lmax 8")]], None),
    "wu2020_fig7": ("Wu 2020 Fig. 7: interpolants on an 8^3 grid",
                    [[("reference", "per-vertex reference"), ("hermite", "Hermite"), ("trilinear", "trilinear"),
                      ("taylor", "Taylor")],
                     [None, ("hermite-error", "10 x error"), ("trilinear-error", "10 x error"),
                      ("taylor-error", "10 x error")]], "wu2020_fig7.csv"),
    "hvl2022_table2": ("HVL 2022 Table 2 / Fig. 10 stand-in: one-bounce indirect light, same virtual lights",
                       [[("reference", "Mitsuba path-traced reference"), ("hvl-400", "HVL 400, 5 bands (10a)"),
                         ("vpl-400", "VPL 400 (10b)"), ("vpl-1928", "VPL 1928 (10c)"),
                         ("vsl-400x25", "VSL 400 x 25 samples (10d)"), ("vsl-256x9", "VSL 256 x 9 samples (10e)")],
                        [None, ("hvl-400-error", "2 x |error|"), ("vpl-400-error", "2 x |error|"),
                         ("vpl-1928-error", "2 x |error|"), ("vsl-400x25-error", "2 x |error|"),
                         ("vsl-256x9-error", "2 x |error|")]], None),
    "wu2020_fig12": ("Wu 2020 Fig. 12: a two-sided light inside the grid's box",
                     [[("reference", "per-vertex reference"), ("grid8", "8^3 Hermite"), ("grid32", "32^3 Hermite")],
                      [None, ("grid8-error", "10 x error"), ("grid32-error", "10 x error")]], None),
}


def panel_figure(name, tables, out):
    title, rows, scan = PANEL_FIGURES[name]
    panels = os.path.join(out, "panels")
    files = [[os.path.join(panels, f"{name}-{c[0]}.png") if c else None for c in row] for row in rows]
    have = [os.path.exists(f) for row in files for f in row if f]
    if not any(have) or (name != "hvl2022_table2" and not all(have)):
        print(f"plot.py: panels of {name} not found in {panels}, skipped", file=sys.stderr)
        return
    scan_rows = read_csv(os.path.join(tables, scan)) if scan else None
    ncol, nrow = max(len(r) for r in rows), len(rows) + (1 if scan_rows else 0)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.2 * ncol, 2.6 * nrow), squeeze=False)
    for r, row in enumerate(rows):
        for c in range(ncol):
            ax = axes[r][c]
            ax.axis("off")
            if c < len(row) and row[c] and os.path.exists(files[r][c]):
                ax.imshow(plt.imread(files[r][c]))
                ax.set_title(row[c][1], fontsize=8)
            elif c < len(row) and row[c]:  # HVL Table 2 without the oracle venv: no reference, no errors
                ax.text(0.5, 0.5, row[c][1] + ":\nno reference\n(oracle venv absent)", ha="center", va="center",
                        fontsize=8, transform=ax.transAxes)
    if scan_rows:
        for c in range(ncol):
            axes[-1][c].remove()
        ax = fig.add_subplot(nrow, 1, nrow)
        x = [int(p["x"]) for p in scan_rows]
        for key in [k for k in scan_rows[0] if k not in ("x", "receiver")]:
            ax.plot(x, [float(p[key]) for p in scan_rows], linewidth=1, label=key.replace("_", " "))
        ax.set_xlabel("pixel along the scanline (the middle row of the receivers)")
        ax.set_ylabel("luminance x exposure")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    save(fig, out, name, exts=("png",))  # raster panels: an SVG would only embed them


def agrid(rows, out):
    """bench/bench_agrid.c: rel. MAE vs nodes and vs fill time, uniform and each adaptive kind, per scene."""
    kinds = OrderedDict([("uniform", ("o", "tab:blue")), ("max", ("s", "tab:red")), ("mean", ("^", "tab:green")),
                         ("budget", ("v", "tab:orange"))])
    for scene in OrderedDict((r["scene"], 1) for r in rows):
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
        for ax, xkey, xlabel in ((axes[0], "nodes", "nodes"), (axes[1], "fill_s", "fill time (s)")):
            for kind, (marker, color) in kinds.items():
                pts = sorted((float(r[xkey]), float(r["rel_mae"])) for r in rows if r["scene"] == scene and r["kind"] == kind)
                if pts:
                    ax.plot(*zip(*pts), marker=marker, color=color, linestyle="-" if kind == "uniform" else "none",
                            label=kind)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(xlabel)
            ax.set_ylabel("rel. MAE of the coefficients")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
        fig.suptitle(f"{scene}: adaptive vs uniform grids (lmax 8, Hermite)")
        save(fig, out, f"agrid_{scene}")


def agrid_image(rows, out):
    """bench/bench_agrid.c, rendered scenes: image rel. MAE vs nodes and vs fill time, uniform grids and
    adaptive ones (tolerance-driven per coarse resolution, budget-driven), uniform 32^3's error dashed."""
    styles = (("uniform", "o", "tab:blue", "-"), ("mean", "^", "tab:green", ":"), ("budget", "v", "tab:orange", "-"),
              ("mean-recv", "s", "tab:red", ":"), ("budget-recv", "D", "tab:purple", "-"),  # -recv: shl_agrid_set_receivers
              ("mean-wrecv", "P", "tab:brown", ":"), ("budget-wrecv", "X", "tab:olive", "-"))  # pixel-weighted receivers
    for scene in OrderedDict((r["scene"], 1) for r in rows):
        srows = [r for r in rows if r["scene"] == scene]
        u32 = [float(r["rel_mae"]) for r in srows if r["kind"] == "uniform" and r["res"] == "32"]
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
        for ax, xkey, xlabel in ((axes[0], "nodes", "nodes"), (axes[1], "fill_s", "fill time (ms)")):
            for kind, marker, color, ls in styles:
                groups = [None] if kind == "uniform" else OrderedDict((r["res"], 1) for r in srows if r["kind"] == kind)
                for res in groups:  # uniform: one curve over its resolutions; adaptive: one per coarse resolution
                    pts = sorted((float(r[xkey]) * (1e3 if xkey == "fill_s" else 1.0), float(r["rel_mae"]))
                                 for r in srows if r["kind"] == kind and res in (None, r["res"]))
                    label = kind if kind == "uniform" else f"{kind}, coarse {res}^3"
                    if not pts:
                        continue
                    ax.plot(*zip(*pts), marker=marker, color=color, linestyle=ls, label=label,
                            alpha=1.0 if not kind.startswith("mean") or res == "4" else 0.55)
            if u32:
                ax.axhline(u32[0], color="tab:blue", linestyle="--", linewidth=0.8, label="uniform 32^3")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(xlabel)
            ax.set_ylabel("image MAE / mean radiance")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
        fig.suptitle(f"{scene} rendered: adaptive (SHL_AGRID_MEAN) vs uniform grids (lmax 8, Hermite)")
        save(fig, out, f"agrid_image_{scene}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tables", default="build/bench-tables/tables", help="directory of the CSV files")
    ap.add_argument("--out", default="build/bench-tables/plots", help="output directory")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    for name, fn in (("accuracy_vs_time.csv", accuracy_vs_time), ("wu2020_fig8.csv", wu_fig8),
                     ("wu2020_fig9.csv", wu_fig9), ("hvl2022_table1.csv", hvl_table1), ("bench_agrid.csv", agrid),
                     ("bench_agrid_image.csv", agrid_image)):
        rows = read_csv(os.path.join(args.tables, name))
        if rows:
            fn(rows, args.out)
    rows = read_csv(os.path.join(args.tables, "wu2020_fig4.csv"))
    if rows:
        wu_fig4(rows, args.out, args.tables)
    rows = read_csv(os.path.join(args.tables, "annen2004_fig8.csv"))
    if rows:
        annen_fig8(rows, args.out)
    rows = read_csv(os.path.join(args.tables, "wu2020_fig6.csv"))
    if rows:
        wu_fig6(rows, args.out)
    for name in PANEL_FIGURES:
        panel_figure(name, args.tables, args.out)


if __name__ == "__main__":
    main()
