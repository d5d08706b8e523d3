#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Benchmark (not a test) of the quality stage: our mesher at size h beside TetGen's quality mesh.

    bench/refine_vs_tetgen.py [MODELS_OR_FOLDERS ...] [--divisions 20] [--modes exact,rounded]
                              [--timeout S] [--png FILE] [--markdown FILE]

For each surface (default: tests/data/paper and tests/data/corpus), h = bounding-box diagonal /
divisions. Both run through the comparison of ``fembsptet compare`` (FemBspTet/compare/
comparison.py), each in a process of its own with a timeout, and every mesh is read back and
evaluated by the same code. Ours: the core then the quality stage at size h (``{"size": h,
"surface_points": mode}``), once per mode. TetGen: ``tetgen -pq1.414a<V>`` with V = h^3 /
(6 sqrt 2) (the volume of the regular tet of edge h). "valid" is our exact checker: against the
input surface for a mesh without boundary Steiner points, else against the mesh's own boundary
(TetGen's surface Steiner points are rounded; so are ours in rounded mode).
Printed per model: validity, tets, min / 1st percentile dihedral angle, seconds, and the ratios
ours / TetGen; then the share of models where our min dihedral >= TetGen's, how many tet counts
are within +-20 %, and the median count ratio. The PNG puts the dihedral histograms side by side.
Models the core cannot mesh are listed with the core's message. Default outputs:
docs/benchmarks/refine-vs-tetgen.md and docs/benchmarks/refine-vs-tetgen.png.
"""

import argparse
import json
import os
import statistics
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from FemBspTet.compare.comparison import OURS, TETGEN_PQ, compare  # noqa: E402
from FemBspTet.io.surface_io import read_surface  # noqa: E402


def _models(args):
    paths = []
    for a in args or [os.path.join(ROOT, "tests", "data", "paper"),
                      os.path.join(ROOT, "tests", "data", "corpus")]:
        if os.path.isdir(a):
            paths += sorted(os.path.join(a, f) for f in os.listdir(a) if f.endswith(".off"))
        else:
            paths.append(a)
    return paths


def _as_dict(row):
    """A comparison row (FemBspTet.compare.comparison.Row) as this script's dict."""
    if row.status != "ok":
        return {"error": f"{row.status}: {row.message}"[:120]}
    return {"tets": row.tets, "min": row.min_dihedral_deg, "p1": row.p1_dihedral_deg,
            "hist": row.dihedral_histogram, "seconds": row.seconds, "valid": row.valid,
            "command": row.command}


def run_ours(surface, h, mode, timeout):
    row = compare(surface, size=h, timeout=timeout, meshers=(OURS,),
                  ours_options={"surface_points": mode}).rows[0]
    return _as_dict(row)


def run_tg(surface, h, timeout):
    return _as_dict(compare(surface, size=h, timeout=timeout, meshers=(TETGEN_PQ,)).rows[0])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", nargs="*")
    ap.add_argument("--divisions", type=float, default=20.0)
    ap.add_argument("--modes", default="exact,rounded")
    ap.add_argument("--timeout", type=float, default=600.0)
    ap.add_argument("--png", default=os.path.join(ROOT, "docs", "benchmarks", "refine-vs-tetgen.png"))
    ap.add_argument("--markdown", default=os.path.join(ROOT, "docs", "benchmarks", "refine-vs-tetgen.md"))
    ap.add_argument("--json", default=None, help="write every row (unrounded figures, histograms) here")
    args = ap.parse_args()
    modes = [m for m in args.modes.split(",") if m]
    rows = []
    header = (f"{'model':<22}{'mode':<8}{'ours':>8}{'tets':>9}{'min':>7}{'p1':>7}{'s':>7}"
              f"{'tetgen':>8}{'tets':>9}{'min':>7}{'p1':>7}{'s':>7}{'tets×':>7}{'min≥':>6}")
    print(header)
    for path in _models(args.models):
        name = os.path.splitext(os.path.basename(path))[0]
        surface = read_surface(path)
        h = float(np.linalg.norm(surface.points.max(0) - surface.points.min(0))) / args.divisions
        tg = None
        for mode in modes:
            ours = run_ours(surface, h, mode, args.timeout)
            if "error" in ours:
                print(f"{name:<22}{mode:<8}  core/refine failed: {ours['error']}")
                rows.append({"name": name, "mode": mode, "ours": ours, "tg": None})
                if mode == modes[0]:
                    break  # the core itself failed: the other modes fail the same way
                continue
            if tg is None:
                tg = run_tg(surface, h, args.timeout)
            row = {"name": name, "mode": mode, "ours": ours, "tg": tg}
            rows.append(row)
            if "error" in tg:
                print(f"{name:<22}{mode:<8}{'VALID':>8}{ours['tets']:>9}{ours['min']:>7.2f}"
                      f"{ours['p1']:>7.2f}{ours['seconds']:>7.2f}  tetgen failed: {tg['error']}")
                continue
            ratio = ours["tets"] / tg["tets"]
            row["ratio"] = ratio
            row["min_ge"] = ours["min"] >= tg["min"]
            print(f"{name:<22}{mode:<8}{'VALID' if ours['valid'] else 'INVALID':>8}{ours['tets']:>9}"
                  f"{ours['min']:>7.2f}{ours['p1']:>7.2f}{ours['seconds']:>7.2f}"
                  f"{'valid' if tg['valid'] else 'invalid':>8}{tg['tets']:>9}{tg['min']:>7.2f}"
                  f"{tg['p1']:>7.2f}{tg['seconds']:>7.2f}{ratio:>7.2f}{'yes' if row['min_ge'] else 'no':>6}")
    print()
    summary = []
    for mode in modes:
        done = [r for r in rows if r["mode"] == mode and "ratio" in r]
        if not done:
            continue
        ge = sum(r["min_ge"] for r in done)
        within = sum(0.8 <= r["ratio"] <= 1.2 for r in done)
        ten = sum(r["ours"]["min"] >= 10 for r in done)
        line = (f"{mode}: {len(done)} models meshed; all valid: "
                f"{all(r['ours']['valid'] for r in done)}; min dihedral >= TetGen's on {ge}/{len(done)} "
                f"({100.0 * ge / len(done):.0f}%); >= 10 deg on {ten}/{len(done)}; tet count within "
                f"+-20% on {within}/{len(done)}; median tets ratio "
                f"{statistics.median(r['ratio'] for r in done):.2f}; median min dihedral ours "
                f"{statistics.median(r['ours']['min'] for r in done):.2f} vs TetGen "
                f"{statistics.median(r['tg']['min'] for r in done):.2f}")
        summary.append(line)
        print(line)
    _plot(rows, modes, args.png)
    if args.markdown:
        _markdown(rows, summary, args)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"divisions": args.divisions, "modes": modes, "summary": summary, "rows": rows}, f)


def _plot(rows, modes, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    meshed = [r for r in rows if r["mode"] == modes[0] and "ratio" in r]
    if not meshed:
        return
    cols = 4
    nrows = (len(meshed) + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(4 * cols, 2.6 * nrows), squeeze=False)
    bins = np.arange(181)
    for ax, r in zip(axes.ravel(), meshed):
        for label, hist, color in (
                [(f"ours ({m})", next((x["ours"]["hist"] for x in rows if x["name"] == r["name"]
                                       and x["mode"] == m and "hist" in x["ours"]), None), c)
                 for m, c in zip(modes, ("tab:blue", "tab:green"))]
                + [("tetgen -pq1.414a", r["tg"]["hist"], "tab:red")]):
            if hist is None:
                continue
            h = np.asarray(hist, float)
            ax.step(bins[:-1], h / max(h.sum(), 1), where="post", label=label, color=color, lw=1)
        ax.set_yscale("log")
        ax.set_xlim(0, 180)
        ax.set_title(f"{r['name']}: min {r['ours']['min']:.1f} vs {r['tg']['min']:.1f} deg", fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in axes.ravel()[len(meshed):]:
        ax.axis("off")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("dihedral angle histograms (fraction of angles per degree, log scale)")
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(png)), exist_ok=True)
    fig.savefig(png, dpi=90)
    print(f"histograms: {png}")


def _deg(x):
    """An angle in degrees for the report: two decimals, or two significant digits below 0.1
    (so that 0.0004 and 0.003, both "0.00" with two decimals, can be told apart)."""
    return f"{x:.2f}" if x >= 0.1 or x == 0 else f"{x:.2g}"


def _markdown(rows, summary, args):
    lines = [f"h = bounding-box diagonal / {args.divisions:g}; TetGen: `tetgen -pq1.414a<V>`, "
             "V = h^3/(6 sqrt 2)", "",
             "| model | mode | ours tets | ours min / p1 dihedral | ours s | TetGen tets | TetGen min / p1 | "
             "TetGen s | tets ratio | TetGen mesh exact-valid |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        o, t = r["ours"], r["tg"]
        if "error" in o:
            lines.append(f"| {r['name']} | {r['mode']} | failed: {o['error']} | | | | | | | |")
        elif t is None or "error" in t:
            lines.append(f"| {r['name']} | {r['mode']} | {o['tets']} | {_deg(o['min'])} / {o['p1']:.2f} "
                         f"| {o['seconds']:.1f} | tetgen failed | | | | |")
        else:
            lines.append(f"| {r['name']} | {r['mode']} | {o['tets']} | {_deg(o['min'])} / {o['p1']:.2f} | "
                         f"{o['seconds']:.1f} | {t['tets']} | {_deg(t['min'])} / {t['p1']:.2f} | "
                         f"{t['seconds']:.1f} | {r['ratio']:.2f} | {'yes' if t['valid'] else 'no'} |")
    lines += [""] + [f"- {s}" for s in summary]
    with open(args.markdown, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
