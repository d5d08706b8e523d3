#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Benchmark (not a test): how our core's time and peak memory grow with the input size, beside
`tetgen -pY` and `tetgen -pq1.414` on the same surfaces.

    bench/scaling.py [--families sphere,torus,cad] [--sizes 1e3,3e3,1e4,3e4,1e5]
                     [--max-triangles N] [--timeout S] [--ours worker|binary]
                     [--mesher-binary PATH] [--cad-file FILE] [--keep DIR] [--check]
                     [--png FILE] [--json FILE] [--markdown FILE]

Families of closed, outward-oriented, non-self-intersecting triangle surfaces, one per target
size (default 1e3, 3e3, 1e4, 3e4, 1e5 triangles; --sizes picks others, up to 1e6):

* ``sphere``: a cube-sphere of radius 1: each cube face cut into n x n quads (equal-angle
  spacing), 2 triangles each, every vertex projected onto the sphere: 12 n^2 triangles;
* ``torus``: a parametric grid of n (around the axis) by m (around the tube) quads, R = 1,
  r = 0.4, m ~ 0.4 n: 2 n m triangles;
* ``cad``: a CAD part (default ``tests/data/cad/bottle.brep``, the OCCT bottle) tessellated by
  FemBspTet's own ``cad_tessellation.tessellate_shape`` with a linear deflection searched for
  the target count (needs Debian's FreeCAD; skipped with a note otherwise).

Each surface is written as OFF (exact doubles), read back, and checked by the core's exact
surface check (no duplicate point, no degenerate triangle, closed, oriented, no
self-intersection) before any mesher runs.

Each mesher runs as a process of its own, one at a time, measured by
``FemBspTet.peers.process.run_measured`` (wall time of the process, start-up included; peak
RSS from GNU time): ``ours`` is the comparison's worker (``python3 -m
FemBspTet.compare.ours_worker``: core.tetrahedralize, which checks its mesh exactly before
returning, and writes a VTU) or, with ``--ours binary``, ``bsptet_mesh FILE.off --no-check
--write STEM`` (the core's own program timed like TetGen's: reads, checks the surface, meshes,
writes .node/.ele; ``--check`` reads them back and checks them exactly, untimed); TetGen runs as ``tetgen -pYQ`` and ``tetgen -pq1.414Q``. A run over
``--timeout`` is recorded as ``timeout`` (and that mesher is not run on the larger sizes of that
family). ``--check`` also runs our exact checker on every mesh (outside the timed process).

Prints the table (seconds and peak MB per mesher, ratios ours / tetgen -pY) and the fitted
growth exponents: the least-squares slope of log(seconds) and log(peak MB) against
log(triangles) over the finished sizes, per mesher and family (fewer than 3 finished sizes:
"n/a (k points)"). --png draws both on log-log axes; --json writes the raw rows; --markdown a
report with the command, the machine, the versions, the table and the exponents (defaults:
docs/benchmarks/scaling.png, .json and .md).
"""

import argparse
import json
import math
import os
import re
import shutil
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

OURS, TETGEN_PY, TETGEN_PQ = "ours", "tetgen-pY", "tetgen-pq"
MESHERS = (OURS, TETGEN_PY, TETGEN_PQ)
COMMANDS = {TETGEN_PY: "tetgen -pY", TETGEN_PQ: "tetgen -pq1.414"}
FAMILIES = ("sphere", "torus", "cad")
DEFAULT_SIZES = (1e3, 3e3, 1e4, 3e4, 1e5)
TORUS_R, TORUS_r = 1.0, 0.4
DEFAULT_CAD_FILE = os.path.join(ROOT, "tests", "data", "cad", "bottle.brep")


# ------------------------------------------------------------------------------------------
# the surfaces
# ------------------------------------------------------------------------------------------

def cube_sphere(n):
    """``(points, triangles)`` of the cube-sphere of radius 1 with ``n`` x ``n`` quads per cube
    face: 6 n^2 + 2 points, 12 n^2 triangles, counter-clockwise seen from outside."""
    n = int(n)
    if n < 1:
        raise ValueError("n must be at least 1")
    # Lattice points of the cube [0, n]^3 surface, indexed once each (shared by the faces).
    index = {}
    points = []

    def vid(i, j, k):
        key = (i, j, k)
        v = index.get(key)
        if v is None:
            v = index[key] = len(points)
            points.append(key)
        return v

    tris = []
    # Each face: a fixed axis at 0 or n, and two running axes (u, v) chosen so that
    # u x v points outward.
    for axis in range(3):
        a1, a2 = (axis + 1) % 3, (axis + 2) % 3
        for side, (ua, va) in ((n, (a1, a2)), (0, (a2, a1))):
            for i in range(n):
                for j in range(n):
                    q = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        c = [0, 0, 0]
                        c[axis], c[ua], c[va] = side, i + di, j + dj
                        q.append(vid(*c))
                    # Alternate the diagonal in a checkerboard: a symmetric mesh.
                    if (i + j) % 2 == 0:
                        tris += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
                    else:
                        tris += [(q[0], q[1], q[3]), (q[1], q[2], q[3])]
    lattice = np.asarray(points, dtype=np.float64)
    cube = np.tan((lattice / n * 2.0 - 1.0) * (math.pi / 4.0))  # equal-angle spacing
    cube[lattice == 0] = -1.0  # exact corners and edges
    cube[lattice == n] = 1.0
    pts = cube / np.linalg.norm(cube, axis=1)[:, None]
    return pts, np.asarray(tris, dtype=np.int64)


def cube_sphere_n(target):
    """The n whose cube-sphere (12 n^2 triangles) is closest to ``target`` triangles."""
    return max(1, int(round(math.sqrt(float(target) / 12.0))))


def torus(n, m, R=TORUS_R, r=TORUS_r):
    """``(points, triangles)`` of the torus with major radius ``R``, minor ``r``, ``n`` quads
    around the axis and ``m`` around the tube: n m points, 2 n m triangles, outward."""
    n, m = int(n), int(m)
    if n < 3 or m < 3:
        raise ValueError("n and m must be at least 3")
    u = 2.0 * math.pi * np.arange(n) / n
    v = 2.0 * math.pi * np.arange(m) / m
    U, V = np.meshgrid(u, v, indexing="ij")
    rho = R + r * np.cos(V)
    pts = np.stack([rho * np.cos(U), rho * np.sin(U), r * np.sin(V)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a = i * m + j
    b = ((i + 1) % n) * m + j
    c = ((i + 1) % n) * m + (j + 1) % m
    d = i * m + (j + 1) % m
    # d(point)/du x d(point)/dv points outward for this parametrisation: a, b, c counter-clockwise.
    tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return pts, tris.astype(np.int64)


def torus_nm(target, R=TORUS_R, r=TORUS_r):
    """``(n, m)`` with 2 n m close to ``target`` and square-ish quads (m ~ n r / R)."""
    n = max(3, int(round(math.sqrt(float(target) * R / (2.0 * r)))))
    m = max(3, int(round(float(target) / (2.0 * n))))
    return n, m


def sphere_volume():
    return 4.0 / 3.0 * math.pi


def torus_volume(R=TORUS_R, r=TORUS_r):
    return 2.0 * math.pi ** 2 * R * r * r


def signed_volume(points, triangles):
    """Volume enclosed by a closed triangle surface (positive when its normals point out)."""
    p = np.asarray(points, dtype=np.float64)
    t = np.asarray(triangles)
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def edge_defects(triangles):
    """Numbers of (directed edges used more than once, directed edges without their reverse):
    both 0 for a closed, consistently oriented, edge-manifold surface."""
    t = np.asarray(triangles, dtype=np.int64)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    key = e[:, 0] * (int(t.max()) + 1) + e[:, 1]
    rkey = e[:, 1] * (int(t.max()) + 1) + e[:, 0]
    uniq, counts = np.unique(key, return_counts=True)
    repeated = int((counts > 1).sum())
    unmatched = int((~np.isin(rkey, uniq)).sum())
    return repeated, unmatched


def make_surface(family, target, cad_file=DEFAULT_CAD_FILE, log=None):
    """The ``family`` surface with about ``target`` triangles: ``(Surface, note)``."""
    from FemBspTet.kernel.mesh_types import Surface

    if family == "sphere":
        n = cube_sphere_n(target)
        p, t = cube_sphere(n)
        return Surface(p, t, source=f"sphere n={n}"), f"cube-sphere n={n}"
    if family == "torus":
        n, m = torus_nm(target)
        p, t = torus(n, m)
        return Surface(p, t, source=f"torus {n}x{m}"), f"torus n={n} m={m}"
    if family == "cad":
        return cad_surface(target, cad_file, log=log)
    raise ValueError(f"unknown family {family!r}")


def freecad_problem():
    """None when FreeCAD loads in this interpreter, else why not."""
    try:
        from FemBspTet.kernel.freecad_env import import_freecad

        import_freecad()
        import Part  # noqa: F401
    except Exception as e:  # noqa: BLE001 - any failure means: no cad family
        return str(e).splitlines()[0] if str(e) else type(e).__name__
    return None


_CAD_SHAPES = {}


def cad_surface(target, path=DEFAULT_CAD_FILE, log=None, tolerance=0.15, tries=8):
    """The CAD part ``path`` tessellated by FemBspTet (``tessellate_shape``) with the linear
    deflection that gives about ``target`` triangles (count ~ deflection^-a, a fitted as we
    go). Returns ``(Surface, note)``; a solid of several solids is joined into one surface."""
    from FemBspTet.io.cad_tessellation import default_linear_deflection, surfaces_to_single, \
        tessellate_shape
    from FemBspTet.kernel.errors import InputError
    from FemBspTet.kernel.freecad_env import import_freecad

    import_freecad()
    import Part

    shape = _CAD_SHAPES.get(path)
    if shape is None:
        shape = _CAD_SHAPES[path] = Part.read(path)
    d = default_linear_deflection(shape)
    ang = 0.5
    tried = []
    best = None
    failures = []
    for _ in range(tries):
        try:
            surf = surfaces_to_single(tessellate_shape(shape, d, ang, source=path))
        except InputError as e:  # a coarse tessellation can fold: try a bit finer
            failures.append(f"deflection {d:.4g}: {str(e).splitlines()[0][:160]}")
            d *= 0.7
            continue
        count = len(surf.triangles)
        tried.append((d, count))
        if best is None or abs(math.log(count / target)) < abs(math.log(best[1] / target)):
            best = (d, count, surf, ang)
        if abs(count / target - 1.0) <= tolerance:
            break
        slope = 1.0
        if len(tried) >= 2 and tried[-1][1] != tried[-2][1]:
            slope = -(math.log(tried[-1][1]) - math.log(tried[-2][1])) / \
                (math.log(tried[-1][0]) - math.log(tried[-2][0]))
            slope = min(max(slope, 0.3), 3.0)
        d *= (count / target) ** (1.0 / slope)
        if count > target and d > 25.0 * default_linear_deflection(shape):
            ang = min(ang * 1.5, 1.5)  # very coarse: the angular limit is binding
    if best is None:
        raise InputError("no closed tessellation near %d triangles (%s)"
                         % (target, "; ".join(failures)), where=path)
    d, count, surf, a = best
    surf.source = f"{os.path.basename(path)} deflection {d:.4g}"
    return surf, (f"{os.path.basename(path)}, linear deflection {d:.4g} mm, angular {a:.2f} rad")


# ------------------------------------------------------------------------------------------
# running the meshers
# ------------------------------------------------------------------------------------------

def _children_cpu():
    """User + system CPU seconds of this process's waited-for children so far (GNU time and the
    mesher under it; a run killed on timeout is not counted)."""
    import resource

    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


_BINARY_LINE = re.compile(r":\s*(VALID|INVALID|UNCHECKED) tets (\d+) points (\d+).*?seconds ([0-9.]+)")


def run_mesher(mesher, surface, off_path, timeout, workdir, ours="worker", binary=None,
               check=False):
    """One measured run: a dict with status ("ok", "failed", "timeout"), message, seconds,
    peak_mb, tets, nodes, valid (None when not checked), core_seconds (ours, binary only)."""
    from FemBspTet.compare.comparison import MesherFailed, _run_ours, _run_tetgen, evaluate
    from FemBspTet.peers.process import run_measured
    from FemBspTet.kernel.errors import BspTetError

    out = {"mesher": mesher, "status": "ok", "message": "", "seconds": None, "peak_mb": None,
           "tets": None, "nodes": None, "valid": None, "core_seconds": None,
           "cpu_seconds": None}
    os.makedirs(workdir, exist_ok=True)
    before = _children_cpu()
    try:
        if mesher == OURS and ours == "binary":
            # Timed like TetGen's program: mesh and write .node/.ele, no check inside the run
            # (the benchmark's own exact checker reads the files back with --check, untimed).
            stem = os.path.join(workdir, "ours_native")
            out["command"] = f"{os.path.basename(binary)} FILE.off --no-check --write STEM"
            run = run_measured([binary, off_path, "--no-check", "--write", stem], timeout=timeout,
                               cwd=workdir)
            out["seconds"], out["peak_mb"] = run.seconds, run.peak_rss_mb
            if run.timed_out:
                raise MesherFailed("timeout", f"timeout after {timeout:g} s")
            m = _BINARY_LINE.search(run.output)
            if run.returncode != 0 or m is None:
                raise MesherFailed("failed", (run.tail(1) or f"exit {run.returncode}")[:300])
            out["tets"], out["nodes"] = int(m.group(2)), int(m.group(3))
            out["core_seconds"] = float(m.group(4))
            out["cpu_seconds"] = _children_cpu() - before
            if check:
                from FemBspTet.io.volume_io import read_tetgen

                out["valid"] = bool(evaluate([surface], [read_tetgen(stem)])["valid"])
            return out
        if mesher == OURS:
            out["command"] = "python3 -m FemBspTet.compare.ours_worker (core.tetrahedralize)"
            meshes, sec, mb, _files = _run_ours([surface], None, timeout, workdir,
                                                "/usr/bin/python3")
        else:
            out["command"] = COMMANDS[mesher]
            meshes, sec, mb, _files = _run_tetgen([surface], COMMANDS[mesher].split(" -")[1],
                                                  timeout, workdir)
        out["seconds"], out["peak_mb"] = sec, mb
        out["cpu_seconds"] = _children_cpu() - before
        out["tets"] = int(sum(len(x.tets) for x in meshes))
        out["nodes"] = int(sum(len(x.points) for x in meshes))
        if mesher == OURS:
            out["valid"] = True  # core.tetrahedralize checks its mesh exactly before returning
        if check:
            out["valid"] = bool(evaluate([surface], meshes)["valid"])
    except MesherFailed as e:
        out["status"], out["message"] = e.status, str(e)
        if e.status == "timeout":
            out["seconds"] = timeout
    except BspTetError as e:
        out["status"], out["message"] = "failed", str(e).splitlines()[0][:300]
    return out


# ------------------------------------------------------------------------------------------
# fits and report
# ------------------------------------------------------------------------------------------

def fit_exponent(x, y):
    """Least-squares ``(exponent, coefficient)`` of ``y = coefficient * x^exponent`` on log-log
    axes. Raises ValueError for fewer than 2 points or non-positive values."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if len(x) < 2 or len(x) != len(y) or (x <= 0).any() or (y <= 0).any():
        raise ValueError("need at least 2 positive (x, y) pairs")
    if np.ptp(np.log(x)) == 0:
        raise ValueError("need at least 2 different x")
    slope, intercept = np.polyfit(np.log(x), np.log(y), 1)
    return float(slope), float(math.exp(intercept))


def exponent_text(x, y, minimum=3):
    """The fitted exponent as text, or "n/a (k points)" with fewer than ``minimum`` points."""
    if len(x) < minimum:
        return f"n/a ({len(x)} point{'s' if len(x) != 1 else ''})"
    return f"{fit_exponent(x, y)[0]:.2f} ({len(x)} points)"


def local_slopes(rows, family, mesher, timeout):
    """Slopes of log(wall seconds) between consecutive sizes, as text; after a finished size, a
    timeout gives a lower bound (">x": the run took more than ``timeout``)."""
    rr = sorted((r for r in rows if r["family"] == family and r["mesher"] == mesher),
                key=lambda r: r["triangles"])
    out = []
    for a, b in zip(rr, rr[1:]):
        if a["status"] != "ok" or b["triangles"] == a["triangles"]:
            continue
        dx = math.log(b["triangles"] / a["triangles"])
        if b["status"] == "ok":
            out.append(f"{math.log(max(b['seconds'], 1e-3) / max(a['seconds'], 1e-3)) / dx:.2f}")
        elif b["status"] == "timeout":
            out.append(f">{math.log(timeout / max(a['seconds'], 1e-3)) / dx:.2f}")
    return ", ".join(out) or "-"


def exponents(rows, families, meshers, timeout=None):
    """``{(family, mesher): {"time": text, "cpu": text, "memory": text, "time_top3": ...}}``."""
    out = {}
    for fam in families:
        for mesher in meshers:
            if not any(r["family"] == fam and r["mesher"] == mesher for r in rows):
                continue
            done = sorted((r["triangles"], r["seconds"], r["peak_mb"], r.get("cpu_seconds"))
                          for r in rows if r["family"] == fam and r["mesher"] == mesher
                          and r["status"] == "ok")
            tri = [d[0] for d in done]
            sec = [max(d[1], 1e-3) for d in done]
            mb = [d[2] for d in done]
            cpu = [(d[0], max(d[3], 1e-3)) for d in done if d[3] is not None]
            e = {"points": len(done), "time": exponent_text(tri, sec),
                 "cpu": exponent_text([c[0] for c in cpu], [c[1] for c in cpu]),
                 "memory": exponent_text(tri, mb)}
            e["time_top3"] = exponent_text(tri[-3:], sec[-3:]) if len(done) > 3 else "-"
            e["memory_top3"] = exponent_text(tri[-3:], mb[-3:]) if len(done) > 3 else "-"
            e["local"] = local_slopes(rows, fam, mesher, timeout) if timeout else "-"
            out[(fam, mesher)] = e
    return out


def _cell(r, key, fmt):
    if r is None:
        return "-"
    if r["status"] == "timeout":
        return "timeout"
    if r["status"] != "ok":
        return r["status"]
    if r.get(key) is None:
        return "?"
    return fmt.format(r[key])


def _ratio(a, b, key):
    if a is None or b is None or a["status"] != "ok" or b["status"] != "ok" \
            or not b.get(key) or a.get(key) is None:
        return "-"
    return f"{a[key] / b[key]:.1f}"


def table_rows(inputs, rows):
    """The table: one line per input."""
    heads = ["family", "triangles", "ours s", "pY s", "pq s", "ours cpu s", "pY cpu s",
             "ours MB", "pY MB", "pq MB", "time ours/pY", "cpu ours/pY", "MB ours/pY",
             "ours tets", "pY tets", "pq tets"]
    body = []
    for inp in inputs:
        rr = {r["mesher"]: r for r in rows if r["input"] == inp["name"]}
        o, y, q = rr.get(OURS), rr.get(TETGEN_PY), rr.get(TETGEN_PQ)
        body.append([inp["family"], str(inp["triangles"]),
                     _cell(o, "seconds", "{:.2f}"), _cell(y, "seconds", "{:.2f}"),
                     _cell(q, "seconds", "{:.2f}"), _cell(o, "cpu_seconds", "{:.2f}"),
                     _cell(y, "cpu_seconds", "{:.2f}"), _cell(o, "peak_mb", "{:.0f}"),
                     _cell(y, "peak_mb", "{:.0f}"), _cell(q, "peak_mb", "{:.0f}"),
                     _ratio(o, y, "seconds"), _ratio(o, y, "cpu_seconds"),
                     _ratio(o, y, "peak_mb"), _cell(o, "tets", "{:d}"),
                     _cell(y, "tets", "{:d}"), _cell(q, "tets", "{:d}")])
    return heads, body


def text_table(heads, body):
    widths = [max(len(x) for x in col) for col in zip(heads, *body)]
    fmt = "  ".join(("{:<%d}" if i == 0 else "{:>%d}") % w for i, w in enumerate(widths))
    return "\n".join([fmt.format(*heads)] + [fmt.format(*b) for b in body])


def md_table(heads, body):
    lines = ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)]
    return "\n".join(lines + ["| " + " | ".join(b) + " |" for b in body])


def exponent_table(exps):
    heads = ["family", "mesher", "time exponent", "CPU-time exponent", "memory exponent",
             "time, largest 3", "memory, largest 3", "local time slopes"]
    body = [[fam, COMMANDS.get(m, "ours"), e["time"], e["cpu"], e["memory"], e["time_top3"],
             e["memory_top3"], e.get("local", "-")] for (fam, m), e in exps.items()]
    return heads, body


def plot(path, rows, families, timeout):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from FemBspTet.io.atomic_file import atomic_output

    colors = {OURS: "tab:blue", TETGEN_PY: "tab:red", TETGEN_PQ: "tab:orange"}
    styles = {"sphere": ("-", "o"), "torus": ("--", "s"), "cad": (":", "^")}
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8))
    for ax, key, label in ((axes[0], "seconds", "wall seconds (process, start-up included)"),
                           (axes[1], "cpu_seconds", "CPU seconds (user + system)"),
                           (axes[2], "peak_mb", "peak RSS (MB)")):
        for fam in families:
            for m in MESHERS:
                rr = sorted((r for r in rows if r["family"] == fam and r["mesher"] == m),
                            key=lambda r: r["triangles"])
                done = [r for r in rr if r["status"] == "ok" and r.get(key) is not None]
                ls, mk = styles.get(fam, ("-", "o"))
                if done:
                    x = [r["triangles"] for r in done]
                    y = [max(r[key], 1e-3) for r in done]
                    name = "ours" if m == OURS else COMMANDS[m]
                    if len(done) >= 3:
                        name += f" (slope {fit_exponent(x, y)[0]:.2f})"
                    ax.plot(x, y, ls=ls, marker=mk, color=colors[m], ms=4, lw=1.2,
                            label=f"{fam}: {name}")
                if key == "seconds":
                    tos = [r["triangles"] for r in rr if r["status"] == "timeout"]
                    if tos:
                        ax.plot(tos, [timeout] * len(tos), ls="none", marker="x",
                                color=colors[m], ms=8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        if key != "peak_mb":  # guides: slopes 1 and 2 through the median of the smallest size
            xs = sorted({r["triangles"] for r in rows})
            ys = [r[key] for r in rows if r["status"] == "ok" and r.get(key)
                  and r["triangles"] == xs[0]] if xs else []
            if len(xs) >= 2 and ys:
                y0 = float(np.median(ys))
                for k in (1, 2):
                    ax.plot([xs[0], xs[-1]], [y0, y0 * (xs[-1] / xs[0]) ** k], color="0.6",
                            lw=0.8, ls=(0, (1, 3)))
                    ax.annotate(f"~n^{k}", (xs[-1], y0 * (xs[-1] / xs[0]) ** k), fontsize=7,
                                color="0.4")
        ax.set_xlabel("input triangles")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_title("wall time (x: timed out)", fontsize=9)
    axes[1].set_title("CPU time", fontsize=9)
    axes[2].set_title("peak memory", fontsize=9)
    axes[2].legend(fontsize=6.5, loc="upper left")
    fig.tight_layout()
    with atomic_output(path, "wb") as f:
        fig.savefig(f, format="png", dpi=90)
    plt.close(fig)


def parse_sizes(text):
    return [int(round(float(s))) for s in text.split(",") if s.strip()]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--families", default="sphere,torus,cad",
                    help="comma-separated, of sphere, torus, cad (default all three)")
    ap.add_argument("--sizes", default=",".join(f"{s:g}" for s in DEFAULT_SIZES),
                    help="target triangle counts, comma-separated (default 1e3,3e3,1e4,3e4,1e5)")
    ap.add_argument("--max-triangles", type=float, default=None,
                    help="drop the target sizes above this")
    ap.add_argument("--meshers", default=",".join(MESHERS),
                    help="comma-separated, of ours, tetgen-pY, tetgen-pq (default all three)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per run (default 600)")
    ap.add_argument("--ours", choices=("worker", "binary"), default="worker",
                    help="our mesher as the comparison's worker (default, core.tetrahedralize "
                         "in python3) or as the C++ tool --mesher-binary")
    ap.add_argument("--mesher-binary", default=os.path.join(ROOT, "build", "cpp_module",
                                                            "bsptet_mesh"),
                    help="bsptet_mesh for --ours binary (default <repo>/build/cpp_module/)")
    ap.add_argument("--cad-file", default=DEFAULT_CAD_FILE,
                    help="the CAD part of the cad family (default tests/data/cad/bottle.brep)")
    ap.add_argument("--keep", default=None, metavar="DIR",
                    help="write the inputs (and the meshers' files) here and keep them")
    ap.add_argument("--check", action="store_true",
                    help="also run our exact checker on every mesh (untimed)")
    ap.add_argument("--no-validate", action="store_true",
                    help="skip the core's exact check of the generated surfaces")
    ap.add_argument("--png", default=os.path.join(ROOT, "docs", "benchmarks", "scaling.png"))
    ap.add_argument("--json", default=os.path.join(ROOT, "docs", "benchmarks", "scaling.json"), help="the raw rows")
    ap.add_argument("--markdown", default=os.path.join(ROOT, "docs", "benchmarks", "scaling.md"))
    ap.add_argument("--from-json", default=None, metavar="FILE",
                    help="run nothing: print and write the table, plot and report of a JSON "
                         "file an earlier run wrote with --json")
    ap.add_argument("--note", action="append", default=[],
                    help="a line added to the markdown report (repeatable)")
    args = ap.parse_args(argv)
    import shlex

    command = "bench/scaling.py " + shlex.join(sys.argv[1:] if argv is None else argv)

    families = [f for f in args.families.split(",") if f]
    meshers = [m for m in args.meshers.split(",") if m]
    for f in families:
        if f not in FAMILIES:
            ap.error(f"unknown family {f}")
    for m in meshers:
        if m not in MESHERS:
            ap.error(f"unknown mesher {m}")
    sizes = sorted(set(parse_sizes(args.sizes)))
    if args.max_triangles:
        sizes = [s for s in sizes if s <= args.max_triangles]
    if OURS in meshers and args.ours == "binary" and not os.access(args.mesher_binary, os.X_OK):
        ap.error(f"no executable {args.mesher_binary} (build it, or use --ours worker)")

    if args.from_json:
        with open(args.from_json, encoding="utf-8") as f:
            saved = json.load(f)
        command, inputs, rows = saved["command"], saved["inputs"], saved["rows"]
        families, notes = saved["families"], saved["notes"] + list(args.note)
        meshers = [m for m in MESHERS if any(r["mesher"] == m for r in rows)]
        args.timeout, args.ours = saved["timeout"], saved["ours"]
        elapsed, env = saved.get("elapsed_seconds", 0.0), saved.get("environment")
        return write_outputs(args, command, families, meshers, inputs, rows, notes, elapsed,
                             env)

    notes = list(args.note)
    if "cad" in families:
        why = freecad_problem()
        if why:
            notes.append(f"cad family skipped: FreeCAD does not load ({why})")
            print(notes[-1])
            families.remove("cad")

    own = args.keep is None
    workdir = tempfile.mkdtemp(prefix="fembsptet_scaling_") if own else args.keep
    os.makedirs(workdir, exist_ok=True)
    from FemBspTet.kernel import core
    from FemBspTet.kernel.errors import BspTetError
    from FemBspTet.io.surface_io import read_surface, write_surface

    inputs, rows = [], []
    stopped = set()  # (family, mesher) that timed out: not run on larger sizes
    started = time.time()
    try:
        for target in sizes:
            for fam in families:
                t0 = time.time()
                try:
                    surf, note = make_surface(fam, target, args.cad_file, log=print)
                except BspTetError as e:
                    msg = f"{fam} {target}: could not make the surface: {e}"
                    print(msg)
                    notes.append(msg)
                    continue
                name = f"{fam}_{target}"
                off = os.path.join(workdir, name + ".off")
                write_surface(off, surf)
                surf = read_surface(off)  # exactly what the meshers read
                p, t = surf.points, surf.triangles
                rep, unm = edge_defects(t)
                vol = signed_volume(p, t)
                problem = None
                if rep or unm:
                    problem = f"not closed/oriented ({rep} repeated, {unm} unmatched edges)"
                elif vol <= 0:
                    problem = f"signed volume {vol:g} <= 0"
                elif not args.no_validate:
                    try:
                        core.check_surface(surf)
                    except BspTetError as e:
                        problem = "core surface check: " + str(e).splitlines()[0][:200]
                inp = {"name": name, "family": fam, "target": target, "triangles": int(len(t)),
                       "points": int(len(p)), "note": note, "volume": vol,
                       "seconds_to_make": round(time.time() - t0, 2),
                       "validated": problem is None and not args.no_validate,
                       "problem": problem}
                print(f"{name}: {len(t)} triangles, {len(p)} points ({note}); "
                      + (problem or "surface check passed" if not args.no_validate
                         else "not checked"), flush=True)
                if problem:
                    notes.append(f"{name}: {problem}; not meshed")
                    continue
                inputs.append(inp)
                for m in meshers:
                    if (fam, m) in stopped:
                        r = {"mesher": m, "status": "not run",
                             "message": "timed out on a smaller size", "seconds": None,
                             "peak_mb": None, "tets": None, "nodes": None, "valid": None}
                    else:
                        rundir = os.path.join(workdir, name + "." + m)
                        r = run_mesher(m, surf, off, args.timeout, rundir, args.ours,
                                       args.mesher_binary, args.check)
                        if not args.keep:
                            shutil.rmtree(rundir, ignore_errors=True)
                        if r["status"] == "timeout":
                            stopped.add((fam, m))
                    r.update(input=name, family=fam, triangles=inp["triangles"])
                    rows.append(r)
                    print(f"  {m:10s} {r['status']:8s} "
                          + (f"{r['seconds']:8.2f} s {r['peak_mb']:8.0f} MB "
                             f"{r['tets']} tets {r['nodes']} nodes"
                             if r["status"] == "ok" else r["message"]), flush=True)
    finally:
        if own:
            shutil.rmtree(workdir, ignore_errors=True)
    elapsed = time.time() - started
    return write_outputs(args, command, families, meshers, inputs, rows, notes, elapsed, None)


def write_outputs(args, command, families, meshers, inputs, rows, notes, elapsed, env):
    """Prints the table and the exponents; writes --json, --png and --markdown."""
    from FemBspTet.compare.benchmark import environment

    if env is None:
        env = [(k, v) for k, v in environment() if k != "Gmsh"] + _ours_environment(args)
    heads, body = table_rows(inputs, rows)
    exps = exponents(rows, families, meshers, args.timeout)
    eh, eb = exponent_table(exps)
    print()
    print(text_table(heads, body))
    print()
    print("growth exponents (least-squares slope on log-log over the finished sizes):")
    print(text_table(eh, eb))

    from FemBspTet.io.atomic_file import atomic_output

    if args.json:
        with atomic_output(args.json) as f:
            json.dump({"command": command, "timeout": args.timeout, "ours": args.ours,
                       "elapsed_seconds": round(elapsed, 1), "families": families,
                       "environment": env,
                       "inputs": inputs, "rows": rows, "notes": notes,
                       "exponents": {f"{k[0]} {k[1]}": v for k, v in exps.items()}},
                      f, indent=1)
    if args.png:
        plot(args.png, rows, families, args.timeout)
    if args.markdown:
        text = report_markdown(command, args, inputs, heads, body, eh, eb, notes, elapsed, env)
        with atomic_output(args.markdown) as f:
            f.write(text)
    return 0


def _ours_environment(args):
    """Which build of our core ran: ``[("ours", text)]``."""
    import glob
    import hashlib

    if args.ours == "binary":
        path = args.mesher_binary
    else:
        so = sorted(glob.glob(os.path.join(ROOT, "FemBspTet", "_bsptet*.so")))
        if not so:
            return [("ours", "FemBspTet/_bsptet*.so not found")]
        path = so[0]
    with open(path, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()[:16]
    name = path if args.ours == "binary" else "FemBspTet/" + os.path.basename(path)
    return [("ours", f"{name} (sha256 {digest}...)")]


def report_markdown(command, args, inputs, heads, body, eh, eb, notes, elapsed, env):
    if " --note " in command:  # the notes are printed below, not in the command
        command = command[:command.index(" --note ")] + " --note ..."
    lines = ["# Scaling: FemBspTet's core beside TetGen, 10^3 to 10^6 input triangles", "",
             f"Made by `{command}` in {elapsed / 60:.1f} min.", "",
             "| machine and versions | |", "|---|---|"]
    lines += [f"| {k} | {v} |" for k, v in env]
    lines += ["", "How to read it:",
              "- Each mesher ran as its own process, one at a time, on the same OFF file; "
              "seconds is that process's wall time (start-up included), MB its peak resident "
              "memory (GNU time).",
              "- ours: " + ("`bsptet_mesh FILE.off --no-check --write STEM`, the core's own program "
                            "timed like TetGen's (reads, checks the surface exactly, meshes, writes "
                            ".node/.ele; the mesh is checked only with --check, outside the timed "
                            "run)." if args.ours == "binary" else
                            "the comparison's worker `python3 -m FemBspTet.compare.ours_worker` "
                            "(starts Python and numpy, reads the OFF, core.tetrahedralize, which "
                            "checks the surface and the mesh exactly, writes a VTU)."),
              "- tetgen -pY: no Steiner point on the surface, no quality bound; tetgen "
              "-pq1.414: radius-edge bound 1.414 (no volume bound), surface Steiner points "
              "allowed. Both with Q (quiet), writing .node/.ele.",
              f"- A run over {args.timeout:g} s is `timeout`; a mesher that timed out is not "
              "run on the larger sizes of that family (`not run`).",
              "- cpu s: user + system CPU seconds of the mesher's process (getrusage of the "
              "waited-for children; none for a run killed on timeout). On a shared machine it "
              "moves less than the wall time.",
              "- Exponent: least-squares slope of log(seconds) (or log(CPU seconds), "
              "log(peak MB)) against "
              "log(triangles) over the finished sizes; with fewer than 3 finished sizes it is "
              "not fitted. Start-up and fixed costs flatten the small sizes, so the slope over "
              "the largest 3 sizes is given too. Runs that timed out are left out of the fits, "
              "which biases a mesher's exponent low when its larger sizes timed out: the local "
              "slopes (between consecutive sizes, wall time) show it, a timeout after a finished "
              "size giving a lower bound (\">x\").",
              "", "## Inputs", "",
              "| input | triangles | points | how | made in s |", "|---|---|---|---|---|"]
    lines += [f"| {i['name']} | {i['triangles']} | {i['points']} | {i['note']} | "
              f"{i['seconds_to_make']} |" for i in inputs]
    lines += ["", "All inputs passed the core's exact surface check (closed, oriented, no "
              "duplicate point, no degenerate triangle, no self-intersection)."
              if all(i["validated"] for i in inputs) else
              "Not every input went through the core's exact surface check (--no-validate).",
              "", "## Time and memory", "", md_table(heads, body), "",
              "## Growth exponents", "", md_table(eh, eb), ""]
    if args.png:
        lines += [f"![time and memory against input size]({os.path.basename(args.png)})", ""]
    if notes:
        lines += ["## Notes", ""] + [f"- {n}" for n in notes] + [""]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
