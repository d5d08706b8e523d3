# SPDX-License-Identifier: LGPL-2.1-or-later
"""The comparison over a folder of models, as a markdown report (``fembsptet benchmark``).

    entries = run_benchmark(model_paths(["tests/data/corpus"]), timeout=300)
    write_report("out/compare-report.md", entries, command="fembsptet benchmark ...")

Each model is read (a CAD file is tessellated once, as ``fembsptet mesh`` does) and given to
:func:`.comparison.compare`; every mesher run has the time limit ``timeout`` (a run over it is a
``timeout`` row). The report states the machine and the versions it ran on, gives one table row
per model and mesher, the ratios against ``tetgen -pY`` (time, tets, Steiner points, min
dihedral angle) with their medians, and a PNG with the dihedral-angle histograms.
"""

import dataclasses
import os
import platform
import statistics
import subprocess
import json
import numpy as np
import re
import tempfile
import time

from ..io.atomic_file import atomic_output
from ..io.formats import CAD_EXTENSIONS, SURFACE_EXTENSIONS
from ..io.inputs import load_input
from ..kernel.errors import BspTetError
from ..kernel.paths import ADDON_DIR
from ..peers.gmsh import gmsh_version
from ..peers.process import DEFAULT_TIMEOUT
from .comparison import (COLORS, COLUMNS, compare, Comparison, draw_histograms, GMSH, MESHERS,
                         OURS, OURS_NATIVE, Row, row_label, TETGEN_PY)

#: Extensions the benchmark takes from a folder (the inputs of ``fembsptet mesh``).
MODEL_EXTENSIONS = SURFACE_EXTENSIONS + CAD_EXTENSIONS


@dataclasses.dataclass
class Entry:
    name: str
    path: str
    comparison: object = None  #: a Comparison, or None when the input could not be read
    error: str = ""  #: why the input could not be read or tessellated


def model_paths(args, extensions=MODEL_EXTENSIONS):
    """Files named in ``args`` and the files of the folders named there whose extension is one
    of ``extensions``, each folder's sorted."""
    paths = []
    for a in args:
        if os.path.isdir(a):
            paths += sorted(os.path.join(a, f) for f in os.listdir(a)
                            if os.path.splitext(f)[1].lower() in extensions)
        else:
            paths.append(a)
    return paths


#: ``repeats``: runs shorter than this many seconds are repeated (their times vary by tens of
#: percent from run to run on a shared machine; a long run's do not).
REPEAT_BELOW_SECONDS = 1.0


def run_benchmark(paths, timeout=DEFAULT_TIMEOUT, divisions=None, meshers=None, log=None, repeats=1):
    """Compares the meshers on every model. ``divisions``: None compares the default meshes;
    N runs every mesher at size h = bounding-box diagonal / N. ``log(text)`` gets one line per
    model as it is done. ``repeats`` > 1: a mesher whose first run took less than
    REPEAT_BELOW_SECONDS runs ``repeats`` times in all, the meshers taking turns, and its seconds
    are the median of its runs (its other figures are the first run's). Returns a list of
    :class:`Entry`."""


    entries = []
    for path in paths:
        name = os.path.splitext(os.path.basename(path))[0]
        entry = Entry(name, path)
        try:
            surfaces = load_input(path)
        except BspTetError as e:
            entry.error = str(e).splitlines()[0][:200]
        else:
            size = None
            if divisions:
                lo = np.min([s.points.min(0) for s in surfaces], axis=0)
                hi = np.max([s.points.max(0) for s in surfaces], axis=0)
                size = float(np.linalg.norm(hi - lo)) / divisions
            entry.comparison = compare(surfaces, size=size, timeout=timeout,
                                       meshers=meshers or MESHERS, source=name)
            _repeat_short_runs(entry.comparison, surfaces, size, timeout, repeats)
        entries.append(entry)
        if log is not None:
            log(_log_line(entry))
    return entries


def _repeat_short_runs(comparison, surfaces, size, timeout, repeats):
    """Replaces the seconds of the short successful rows by the median over ``repeats`` runs."""

    short = [r for r in comparison.rows
             if r.status == "ok" and r.seconds is not None and r.seconds < REPEAT_BELOW_SECONDS]
    if repeats <= 1 or not short:
        return
    times = {r.mesher: [r.seconds] for r in short}
    for _ in range(repeats - 1):
        again = compare(surfaces, size=size, timeout=timeout, meshers=tuple(times),
                        source=comparison.source)
        for r in again.rows:
            if r.status == "ok" and r.seconds is not None:
                times[r.mesher].append(r.seconds)
    for r in short:
        r.seconds = statistics.median(times[r.mesher])


def _log_line(entry):
    if entry.comparison is None:
        return f"{entry.name}: input: {entry.error}"
    parts = []
    for r in entry.comparison.rows:
        if r.status == "ok":
            parts.append(f"{row_label(r)} {r.tets} tets {r.seconds:.2f} s"
                         + ("" if r.valid else " INVALID"))
        else:
            parts.append(f"{row_label(r)} {r.status}")
    return f"{entry.name}: " + "; ".join(parts)


# ------------------------------------------------------------------------------------------
# ratios against TetGen
# ------------------------------------------------------------------------------------------

#: Ratios against ``tetgen -pY``: (name, function of (row, tetgen row)). Steiner points as
#: (ours + 1) / (TetGen's + 1), so that models where TetGen needs none still count.
RATIOS = (
    ("time", lambda r, t: r.seconds / max(t.seconds, 1e-3)),
    ("tets", lambda r, t: r.tets / max(t.tets, 1)),
    ("Steiner+1", lambda r, t: (r.steiner_points + 1) / (t.steiner_points + 1)),
    ("min dihedral", lambda r, t: r.min_dihedral_deg / t.min_dihedral_deg
     if t.min_dihedral_deg > 0 else float("nan")),
)


def ratios(comparison, mesher):
    """``{ratio name: value}`` of ``mesher``'s row against ``tetgen -pY``'s, or None when one
    of them made no mesh."""
    row, tg = comparison.row(mesher), comparison.row(TETGEN_PY)
    if row is None or tg is None or row.status != "ok" or tg.status != "ok":
        return None
    return {name: f(row, tg) for name, f in RATIOS}


# ------------------------------------------------------------------------------------------
# environment and report
# ------------------------------------------------------------------------------------------

def _first_line(command):
    try:
        out = subprocess.run(command, capture_output=True, text=True, timeout=30)
        text = (out.stdout or out.stderr).strip()
        return text.splitlines()[0] if text else "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def environment():
    """What the figures were measured on: ``[(item, value)]``."""
    cpu = "unknown"
    try:
        for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
            if line.startswith("Model name:"):
                cpu = line.split(":", 1)[1].strip()
    except OSError:
        pass
    ram = "unknown"
    try:
        with open("/proc/meminfo") as f:
            kib = int(f.readline().split()[1])
        ram = f"{kib / 1024 ** 2:.1f} GiB"
    except (OSError, ValueError, IndexError):
        pass
    debian = "unknown"
    try:
        with open("/etc/debian_version") as f:
            debian = f.read().strip()
    except OSError:
        pass
    root = ADDON_DIR
    commit = _first_line(["git", "-C", root, "rev-parse", "--short=12", "HEAD"])
    dirty = _first_line(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"])


    return [("date", time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())),
            ("CPU", f"{cpu} ({os.cpu_count()} logical cores)"), ("RAM", ram),
            ("OS", f"Debian {debian}, {platform.system()} {platform.release()}"),
            ("Python", platform.python_version()),
            ("TetGen", _first_line(["dpkg-query", "-W", "-f", "${Version}", "tetgen"])
             .join(("Debian package tetgen ", ""))),
            ("Gmsh", gmsh_version() or "not installed"),
            ("FemBspTet", f"git {commit}" + (" (with uncommitted changes)"
                                             if dirty not in ("unknown", "") else ""))]


def _short_message(message):
    """``message`` without the comparison's temporary folder (``fembsptet_compare_*/`` in the
    system's temporary directory) and with paths inside the current directory made relative to
    it (a report names no machine's folders)."""

    folder = re.escape(os.path.join(tempfile.gettempdir(), "fembsptet_compare_"))
    message = re.sub(folder + r"[^/\s]*/", "", message)
    return message.replace(os.getcwd() + os.sep, "")


def _cell_text(row, key):
    return row.cell(key) if row.status == "ok" else ""


def report_markdown(entries, command="", png_name=None, env=None, repeats=1):
    """The report as markdown text."""
    env = environment() if env is None else env
    lines = ["# FemBspTet, TetGen and Gmsh on the same surfaces", "",
             f"Made by `{command}`." if command else "", "",
             "| machine and versions | |", "|---|---|"]
    lines += [f"| {k} | {v} |" for k, v in env]
    sizes = {e.comparison.size is None for e in entries if e.comparison is not None}
    lines += ["", "How to read it:",
              "- Each mesher ran as its own process, one at a time; seconds is that process's "
              "wall time (start-up included: our worker starts Python and numpy, about 0.1 s), "
              "peak MB its peak resident memory (GNU time)." +
              (f" A run shorter than {REPEAT_BELOW_SECONDS:g} s was made {repeats} times, the "
               "meshers taking turns: its seconds are the median (its other figures, the first "
               "run's)." if repeats > 1 else ""),
              "- A CAD file is tessellated once; every mesher gets the same triangles.",
              "- Steiner in / bd: nodes that are not input vertices, inside / on the boundary.",
              "- valid: our exact checker. Without boundary Steiner points: positive tets, "
              "conforming, boundary = the input triangulation. With boundary Steiner points: "
              "positive tets, conforming, closed boundary (marked *).",
              "- Gmsh fills the given triangulation (a discrete surface, not remeshed) with "
              "`Mesh.CharacteristicLengthMax` = the mean input edge length" +
              (" (or the size)" if False in sizes else "") + "; Gmsh 4.8 sizes the interior "
              "of a discrete surface from its triangles, so this setting changes little.",
              "- `timeout`: the run exceeded the time limit; `failed`: the mesher's message.",
              ""]
    heads = ["model", "mesher"] + [h for _k, h, _f in COLUMNS]
    lines += ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)]
    for e in entries:
        if e.comparison is None:
            lines.append(f"| {e.name} | input | {e.error} |" + " |" * (len(heads) - 3))
            continue
        for r in e.comparison.rows:
            if r.status != "ok":
                msg = _short_message(r.message).replace("|", "/")[:150]
                lines.append(f"| {e.name} | {row_label(r)} | **{r.status}**: {msg} |"
                             + " |" * (len(heads) - 3))
                continue
            cells = [_cell_text(r, k) for k, _h, _f in COLUMNS]
            if r.steiner_boundary:
                cells[-1] += "*"
            lines.append(f"| {e.name} | {row_label(r)} | " + " | ".join(cells) + " |")
    lines += ["", "## Ratios against `tetgen -pY`", "",
              "Per model where both meshed; Steiner points as (ours + 1) / (TetGen's + 1).", ""]
    names = [n for n, _f in RATIOS]
    lines += ["| model | mesher | " + " | ".join(names) + " |", "|---|---|" + "---|" * len(names)]
    collected = {}
    for e in entries:
        if e.comparison is None:
            continue
        for mesher in (OURS, OURS_NATIVE, GMSH):
            rs = ratios(e.comparison, mesher)
            if rs is None:
                continue
            collected.setdefault(mesher, []).append(rs)
            label = row_label(e.comparison.row(mesher))
            lines.append(f"| {e.name} | {label} | "
                         + " | ".join(f"{rs[n]:.3g}" for n in names) + " |")
    lines += ["", "| medians | models | " + " | ".join(names) + " |",
              "|---|---|" + "---|" * len(names)]
    for mesher, rows in collected.items():
        meds = [statistics.median(r[n] for r in rows if r[n] == r[n]) for n in names]
        label = {OURS: "FemBspTet", OURS_NATIVE: "bsptet_mesh (C++ core)"}.get(mesher, "gmsh -3")
        lines.append(f"| {label} / tetgen -pY | {len(rows)} | "
                     + " | ".join(f"{m:.3g}" for m in meds) + " |")
    lines += ["", _outcome_summary(entries)]
    if png_name:
        lines += ["", "## Dihedral angles", "",
                  f"![dihedral-angle histograms, per model]({png_name})"]
    return "\n".join(lines) + "\n"


def _outcome_summary(entries):
    counts = {}
    for e in entries:
        if e.comparison is None:
            counts.setdefault("input", {}).setdefault("unreadable", 0)
            counts["input"]["unreadable"] += 1
            continue
        for r in e.comparison.rows:
            key = r.status if r.status != "ok" else ("valid" if r.valid else "INVALID")
            c = counts.setdefault(row_label(r), {})
            c[key] = c.get(key, 0) + 1
    parts = [f"{who}: " + ", ".join(f"{n} {k}" for k, n in sorted(c.items()))
             for who, c in counts.items()]
    return f"Outcomes over {len(entries)} models: " + "; ".join(parts) + "."


def plot_benchmark(path, entries, cols=6):
    """One small panel per model with every mesher's dihedral-angle histogram."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt


    shown = [e for e in entries if e.comparison is not None
             and any(r.status == "ok" for r in e.comparison.rows)]
    if not shown:
        return False
    nrows = (len(shown) + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(2.3 * cols, 1.6 * nrows), squeeze=False)
    for ax, e in zip(axes.ravel(), shown):
        draw_histograms(ax, e.comparison.rows, legend=False)
        ax.set_yscale("log")
        ax.set_title(e.name, fontsize=7)
        ax.tick_params(which="both", labelsize=5)
    for ax in axes.ravel()[len(shown):]:
        ax.axis("off")
    from matplotlib.lines import Line2D


    seen = {}
    for e in shown:
        for r in e.comparison.rows:
            if r.status == "ok":
                seen.setdefault(row_label(r), r.mesher)
    handles = [Line2D([], [], color=COLORS.get(m)) for m in seen.values()]
    labels = list(seen)
    fig.legend(handles, labels, loc="upper right", fontsize=7)
    fig.suptitle("dihedral angles, 0-180 deg: fraction per 5 deg (log scale)", fontsize=8)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    with atomic_output(path, "wb") as f:
        fig.savefig(f, format="png", dpi=72)
    plt.close(fig)
    return True


def save_entries(path, entries, command, env):
    """Every figure of the run as JSON (``<stem>.json`` beside the report), so the report can be
    made again (:func:`load_entries`) without running the meshers again."""


    data = {"command": command, "environment": env,
            "entries": [{"name": e.name, "path": e.path, "error": e.error,
                         "comparison": None if e.comparison is None else e.comparison.to_dict()}
                        for e in entries]}
    with atomic_output(path) as f:
        json.dump(data, f)


def load_entries(path):
    """``(entries, command, env)`` from a file written by :func:`save_entries`."""


    with open(path) as f:
        data = json.load(f)
    fields = {f.name for f in dataclasses.fields(Row)}
    entries = []
    for d in data["entries"]:
        c = d["comparison"]
        if c is not None:
            c = Comparison(**{**c, "rows": [Row(**{k: v for k, v in r.items() if k in fields})
                                            for r in c["rows"]]})
        entries.append(Entry(d["name"], d["path"], c, d["error"]))
    return entries, data["command"], [tuple(x) for x in data["environment"]]


def write_report(path, entries, command="", png=True, env=None):
    """Writes the markdown report, ``<stem>.png`` (histograms) and ``<stem>.json`` (every
    figure) beside it. Returns the PNG path or None."""

    env = environment() if env is None else env
    save_entries(os.path.splitext(path)[0] + ".json", entries, command, env)
    png_path = None
    if png:
        png_path = os.path.splitext(path)[0] + ".png"
        if not plot_benchmark(png_path, entries):
            png_path = None
    text = report_markdown(entries, command, os.path.basename(png_path) if png_path else None,
                           env)
    with atomic_output(path) as f:
        f.write(text)
    return png_path
