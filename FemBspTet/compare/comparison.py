# SPDX-License-Identifier: LGPL-2.1-or-later
"""Our mesher, TetGen and Gmsh on the same surface, each mesh evaluated by the same code.

    from FemBspTet.compare.comparison import compare, format_table
    result = compare(surfaces, size=None, timeout=600, workdir="out/cmp")
    print(format_table(result))

The meshers, each a separate process measured by :func:`.process.run_measured` (wall time from
start to exit, peak resident memory of that process):

* ``ours``: :mod:`.ours_worker` (``core.tetrahedralize``; with ``size`` the quality stage at
  that size);
* ``tetgen-pY``: ``tetgen -pY`` (no Steiner point on the surface, no quality bound);
* ``tetgen-pq``: ``tetgen -pq1.414a<V>``, V = h^3 / (6 sqrt 2) the volume of the regular tet of
  edge h (only with ``size``);
* ``gmsh``: Gmsh's 3D mesher on the same triangulation. Without ``size`` it fills the given
  triangulation (``CharacteristicLengthMax`` = the mean input edge length; Gmsh sizes the
  interior from the surface anyway); with ``size`` it first remeshes the surface at that size
  (its ``ClassifySurfaces`` + ``CreateGeometry``), as ``tetgen -pq`` splits surface triangles:
  see :mod:`.gmsh_backend`. The table says which.

A CAD input is tessellated once (by the caller) and every mesher gets the same triangles; a
solid of several solids is meshed solid by solid and the counts are summed.

Every mesh is read back from the file its mesher wrote (our own readers) and evaluated by
:func:`evaluate`: nodes, tets, Steiner points (nodes that are not input vertices, split by
whether they lie on the mesh's boundary), dihedral angles and radius-edge ratios
(``core.tet_quality``) and the exact checker (``core.check_mesh``). A mesh without boundary
Steiner points is checked against the input surface (positive tets, conforming faces, its boundary
is exactly the input triangulation); one with boundary Steiner points (TetGen's ``-pq``, Gmsh when
its boundary recovery splits the surface) cannot have the input triangulation as its boundary, so
it is checked against its own boundary (positive tets, conforming faces, a closed boundary) and the
row says so.

A mesher that is missing is a ``skipped`` row, one that fails a ``failed`` row with its message,
one that runs out of time a ``timeout`` row: :func:`compare` never raises for a mesher.
"""

import dataclasses
import json
import os
import shutil
import tempfile

import numpy as np
from types import SimpleNamespace

from ..io.atomic_file import atomic_output
from ..io.surface_io import write_surface
from ..io.volume_io import read_tet_mesh, read_tetgen
from ..kernel import core
from ..kernel.core import boundary_surface
from ..kernel.errors import BspTetError, InternalError
from ..kernel.mesh_types import Surface, TetMesh
from ..kernel.paths import ADDON_DIR
from ..peers.gmsh import gmsh_available, gmsh_command, mean_edge_length, run_gmsh
from ..peers.process import DEFAULT_TIMEOUT, run_measured, worker_env
from ..peers.tetgen import quality_switches, run_tetgen, tetgen_available
from .ours_worker import ours_mesh_path

OURS, TETGEN_PY, TETGEN_PQ, GMSH = "ours", "tetgen-pY", "tetgen-pq", "gmsh"
#: Our core alone as a native program (``build/cpp_module/bsptet_mesh --no-check``), for timing
#: the core beside TetGen's own program without our Python worker's start-up (about 0.1 s) and
#: in-process check; its mesh is read back and checked here like every other. Opt-in: not in
#: MESHERS, and only without a size (the core makes no quality mesh).
OURS_NATIVE = "ours-native"
#: Every mesher of the default comparison, in table order.
MESHERS = (OURS, TETGEN_PY, TETGEN_PQ, GMSH)

#: Checks applied, by how the mesh's boundary relates to the input.
CHECKS_AGAINST_INPUT = "exact: positive tets, conforming, boundary = input triangulation"
CHECKS_AGAINST_OWN_BOUNDARY = ("exact: positive tets, conforming, closed boundary (boundary "
                               "Steiner points: the boundary is not the input triangulation)")

#: Columns of the table: (Row field, header, format). The task panel shows the same rows.
COLUMNS = (
    ("nodes", "nodes", "{:d}"),
    ("tets", "tets", "{:d}"),
    ("steiner_interior", "Steiner in", "{:d}"),
    ("steiner_boundary", "Steiner bd", "{:d}"),
    ("min_dihedral_deg", "min dih", "{:.2f}"),
    ("p1_dihedral_deg", "1% dih", "{:.2f}"),
    ("median_dihedral_deg", "med dih", "{:.2f}"),
    ("max_radius_edge_ratio", "max r/e", "{:.3g}"),
    ("seconds", "seconds", "{:.3f}"),
    ("peak_rss_mb", "peak MB", "{:.0f}"),
    ("valid", "valid", "{}"),
)


@dataclasses.dataclass
class Row:
    """One mesher's result. Figures are None when it made no mesh (``status`` != "ok")."""

    mesher: str  #: one of MESHERS
    command: str  #: what ran, e.g. "tetgen -pY"
    status: str = "ok"  #: "ok", "failed", "timeout" or "skipped"
    message: str = ""  #: why it failed or was skipped
    nodes: int = None
    tets: int = None
    steiner_interior: int = None
    steiner_boundary: int = None
    min_dihedral_deg: float = None
    p1_dihedral_deg: float = None
    median_dihedral_deg: float = None
    max_radius_edge_ratio: float = None
    seconds: float = None
    peak_rss_mb: float = None
    valid: bool = None
    checks: str = ""  #: which checks ``valid`` is made of
    check_messages: list = dataclasses.field(default_factory=list)
    mesh_files: list = dataclasses.field(default_factory=list)  #: as written by the mesher
    dihedral_histogram: list = dataclasses.field(default_factory=list)  #: 180 one-degree bins

    @property
    def steiner_points(self):
        if self.steiner_interior is None:
            return None
        return self.steiner_interior + self.steiner_boundary

    def cell(self, key):
        """The table's text for column ``key``."""
        value = getattr(self, key)
        if self.status != "ok":
            return "-"
        if key == "valid":
            return "yes" if value else "NO"
        fmt = dict((k, f) for k, _h, f in COLUMNS)[key]
        return "-" if value is None else fmt.format(value)


@dataclasses.dataclass
class Comparison:
    source: str
    input_points: int
    input_triangles: int
    solids: int
    size: float  #: the size asked for, or None
    gmsh_size: float  #: Gmsh's CharacteristicLengthMax
    gmsh_size_note: str  #: where gmsh_size comes from
    rows: list

    def row(self, mesher):
        return next((r for r in self.rows if r.mesher == mesher), None)

    def to_dict(self, histograms=True):
        d = dataclasses.asdict(self)
        for r in d["rows"]:
            r["steiner_points"] = (None if r["steiner_interior"] is None
                                   else r["steiner_interior"] + r["steiner_boundary"])
            if not histograms:
                r.pop("dihedral_histogram")
        return d


class MesherFailed(Exception):
    """A mesher's run did not give a mesh; ``status`` is "failed", "timeout" or "skipped"."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


# ------------------------------------------------------------------------------------------
# evaluation: the same code for every mesh
# ------------------------------------------------------------------------------------------

def _point_keys(points):
    """One hashable byte string per row (``-0.0`` counted as ``0.0``)."""
    a = np.ascontiguousarray(np.asarray(points, dtype=np.float64) + 0.0)
    return a.view(np.dtype((np.void, 24))).ravel()


def steiner_points(surface: Surface, mesh: TetMesh):
    """``(interior, boundary)``: boolean masks over ``mesh.points`` of the nodes that are not
    vertices of ``surface`` (exact coordinates), inside the mesh and on its boundary."""

    new = ~np.isin(_point_keys(mesh.points), _point_keys(surface.points))
    on_boundary = np.zeros(len(mesh.points), dtype=bool)
    on_boundary[np.unique(boundary_surface(mesh).triangles)] = True
    return new & ~on_boundary, new & on_boundary


def evaluate(surfaces, meshes):
    """Counts, quality and validity of ``meshes`` (one per surface, same order), summed over
    the solids. Returns a dict of :class:`Row` fields."""

    out = {"nodes": 0, "tets": 0, "steiner_interior": 0, "steiner_boundary": 0, "valid": True}
    checks, messages = set(), []
    for surface, mesh in zip(surfaces, meshes):
        interior, boundary = steiner_points(surface, mesh)
        out["nodes"] += int(len(mesh.points))
        out["tets"] += int(len(mesh.tets))
        out["steiner_interior"] += int(interior.sum())
        out["steiner_boundary"] += int(boundary.sum())
        if boundary.any():
            reference, what = core.boundary_surface(mesh), CHECKS_AGAINST_OWN_BOUNDARY
        else:
            reference, what = surface, CHECKS_AGAINST_INPUT
        report = core.check_mesh(reference, mesh, max_messages=3, compute_quality=False)
        checks.add(what)
        out["valid"] = out["valid"] and bool(report["valid"])
        messages += list(report["messages"])
    q = core.tet_quality(concatenate_meshes(meshes))
    out.update(min_dihedral_deg=q["min_dihedral_deg"], p1_dihedral_deg=q["p1_dihedral_deg"],
               median_dihedral_deg=q["median_dihedral_deg"],
               max_radius_edge_ratio=q["max_radius_edge_ratio"],
               dihedral_histogram=[int(x) for x in q["dihedral_histogram"]],
               checks="; ".join(sorted(checks)), check_messages=messages[:5])
    return out


def concatenate_meshes(meshes):
    if len(meshes) == 1:
        return meshes[0]
    offsets = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
    return TetMesh(np.vstack([m.points for m in meshes]),
                   np.vstack([m.tets[:, :4] + off for m, off in zip(meshes, offsets)]))


# ------------------------------------------------------------------------------------------
# the meshers
# ------------------------------------------------------------------------------------------

def _error_line(text):
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    msg = lines[-1] if lines else ""
    for prefix in ("fembsptet: ", "error: "):
        if msg.startswith(prefix):
            msg = msg[len(prefix):]
    return msg


def _run_ours(surfaces, size, timeout, workdir, python, options=None):

    opts = dict(options or {})
    if size is not None:
        opts["size"] = float(size)
    paths = []
    for k, s in enumerate(surfaces):
        paths.append(os.path.join(workdir, f"solid{k}.off"))
        write_surface(paths[-1], s)
    run = run_measured([python, "-m", "FemBspTet.compare.ours_worker", json.dumps(opts), workdir]
                       + paths, timeout=timeout, env=worker_env(), cwd=workdir)
    if run.timed_out:
        raise MesherFailed("timeout", f"timeout after {timeout:g} s")
    if run.returncode != 0:
        raise MesherFailed("failed", _error_line(run.output) or f"exit {run.returncode}")
    files = [ours_mesh_path(workdir, p) for p in paths]
    return [read_tet_mesh(f) for f in files], run.seconds, run.peak_rss_mb, files


def core_tool_path():
    """``bsptet_mesh``, the core's command-line program, or None: ``$FEMBSPTET_CORE_TOOL``, else
    the checkout's build (scripts/setup.sh), else an installed addon's ``libexec``."""
    root = ADDON_DIR
    candidates = [os.environ.get("FEMBSPTET_CORE_TOOL")] if os.environ.get(
        "FEMBSPTET_CORE_TOOL") else [os.path.join(root, "build", "cpp_module", "bsptet_mesh"),
                                     os.path.join(root, "libexec", "bsptet_mesh")]
    for path in candidates:
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    return None


def _run_ours_native(surfaces, timeout, workdir):


    exe = core_tool_path()
    if exe is None:
        raise MesherFailed("skipped", "build/cpp_module/bsptet_mesh is not built (scripts/setup.sh)")

    def one(s, t, name):
        src, stem = os.path.join(workdir, f"{name}.native.off"), os.path.join(workdir, f"{name}.native")
        write_surface(src, s)
        run = run_measured([exe, src, "--no-check", "--write", stem], timeout=t, cwd=workdir)
        if run.timed_out:
            raise InternalError(f"bsptet_mesh timed out after {t:g} s")
        if run.returncode != 0:
            lines = [ln for ln in run.output.strip().splitlines() if ln.strip()]
            msg = (lines[0] if lines else f"exit {run.returncode}").split(": ", 1)[-1]
            for prefix in ("INPUT ERROR ", "ERROR "):
                msg = msg[len(prefix):] if msg.startswith(prefix) else msg
            raise InternalError(msg)
        return SimpleNamespace(mesh=read_tetgen(stem), seconds=run.seconds,
                               peak_rss_mb=run.peak_rss_mb, mesh_path=stem)

    meshes, seconds, rss, stems = _run_per_solid(one, surfaces, timeout)
    return meshes, seconds, rss, [st + ext for st in stems for ext in (".node", ".ele")]


def _run_per_solid(run_one, surfaces, timeout):
    """Runs ``run_one(surface, remaining_timeout, name)`` per solid; sums seconds, max memory."""
    meshes, seconds, rss, files = [], 0.0, 0.0, []
    for k, s in enumerate(surfaces):
        remaining = None if timeout is None else max(timeout - seconds, 0.01)
        try:
            r = run_one(s, remaining, f"solid{k}")
        except InternalError as e:
            status = "timeout" if "timed out" in str(e) else "failed"
            raise MesherFailed(status, str(e).splitlines()[0][:300]) from None
        meshes.append(r.mesh)
        seconds += r.seconds
        rss = max(rss, r.peak_rss_mb)
        files.append(r.mesh_path)
    return meshes, seconds, rss, files


def _run_tetgen(surfaces, switches, timeout, workdir):

    if not tetgen_available():
        raise MesherFailed("skipped", "tetgen is not installed (Debian package tetgen)")
    tag = switches.split("a")[0].replace(".", "")

    def one(s, t, name):
        return run_tetgen(s, switches, timeout=t, keep_dir=workdir, name=f"{name}.tetgen_{tag}")

    meshes, seconds, rss, stems = _run_per_solid(one, surfaces, timeout)
    return meshes, seconds, rss, [st + ext for st in stems for ext in (".node", ".ele")]


def _run_gmsh(surfaces, size, timeout, workdir, remesh_surface):

    if not gmsh_available():
        raise MesherFailed("skipped", "gmsh is not installed (Debian package gmsh)")

    def one(s, t, name):
        return run_gmsh(s, size, timeout=t, keep_dir=workdir, name=name,
                        remesh_surface=remesh_surface)

    return _run_per_solid(one, surfaces, timeout)


def tetgen_pY_row(surfaces, timeout=DEFAULT_TIMEOUT, workdir=None):
    """The ``tetgen -pY`` row alone (the FreeCAD mesher object's comparison)."""
    return _mesher_row(TETGEN_PY, surfaces, None, timeout, workdir, None, None, None)


def _mesher_row(mesher, surfaces, size, timeout, workdir, gmsh_size, python, ours_options):

    own_dir = workdir is None
    workdir = workdir or tempfile.mkdtemp(prefix="fembsptet_compare_")
    if mesher == OURS:
        command = "fembsptet" + (f" --size {size:g}" if size is not None else "")
    elif mesher == OURS_NATIVE:
        command = "bsptet_mesh --no-check"
    elif mesher == TETGEN_PY:
        command = "tetgen -pY"
    elif mesher == TETGEN_PQ:
        command = "tetgen -" + quality_switches(size)
    else:

        command = gmsh_command(gmsh_size, remesh_surface=size is not None)
    row = Row(mesher=mesher, command=command)
    try:
        if mesher == OURS:
            meshes, row.seconds, row.peak_rss_mb, files = _run_ours(
                surfaces, size, timeout, workdir, python or DEFAULT_PYTHON, ours_options)
        elif mesher == OURS_NATIVE:
            meshes, row.seconds, row.peak_rss_mb, files = _run_ours_native(surfaces, timeout,
                                                                           workdir)
        elif mesher in (TETGEN_PY, TETGEN_PQ):
            meshes, row.seconds, row.peak_rss_mb, files = _run_tetgen(
                surfaces, command.split(" -")[1], timeout, workdir)
        else:
            meshes, row.seconds, row.peak_rss_mb, files = _run_gmsh(
                surfaces, gmsh_size, timeout, workdir, remesh_surface=size is not None)
        row.mesh_files = [] if own_dir else files
        for k, v in evaluate(surfaces, meshes).items():
            setattr(row, k, v)
    except MesherFailed as e:
        row.status, row.message = e.status, str(e)
    except BspTetError as e:  # a mesh we cannot read back
        row.status, row.message = "failed", str(e).splitlines()[0][:300]
    finally:
        if own_dir:
            shutil.rmtree(workdir, ignore_errors=True)
    return row


#: Interpreter of our worker: Debian's (FreeCAD's modules load there; inside the GUI
#: ``sys.executable`` is FreeCAD itself).
DEFAULT_PYTHON = "/usr/bin/python3"


def compare(surfaces, size=None, timeout=DEFAULT_TIMEOUT, workdir=None, meshers=MESHERS,
            python=None, ours_options=None, source=""):
    """Runs the meshers on ``surfaces`` (a Surface or a list, one per solid). Returns a
    :class:`Comparison`; never raises for a mesher (its row says what happened).

    ``size``: None compares the default meshes (``tetgen -pY``, no ``-pq`` row; Gmsh filling the
    triangulation, at the mean input edge length); H runs our quality stage at size H,
    ``tetgen -pq1.414a<V(H)>`` and Gmsh at H with the surface remeshed. ``workdir``: keep every mesher's files there (else a temporary directory, removed).
    ``ours_options``: more options for our mesher (e.g. ``{"surface_points": "rounded"}``).
    """

    if isinstance(surfaces, Surface):
        surfaces = [surfaces]
    surfaces = list(surfaces)
    if size is not None:
        gmsh_size, note = float(size), "--size (surface remeshed by Gmsh)"
    else:
        all_edges = sum(3 * len(s.triangles) for s in surfaces)
        gmsh_size = sum(mean_edge_length(s) * 3 * len(s.triangles) for s in surfaces) / all_edges
        note = "mean input edge length"
    if workdir is not None:
        os.makedirs(workdir, exist_ok=True)
    rows = []
    for mesher in meshers:
        if (mesher == TETGEN_PQ and size is None) or (mesher == OURS_NATIVE and size is not None):
            continue
        rows.append(_mesher_row(mesher, surfaces, size, timeout, workdir, gmsh_size, python,
                                ours_options))
    return Comparison(source=source or " + ".join(s.source for s in surfaces if s.source),
                      input_points=sum(len(s.points) for s in surfaces),
                      input_triangles=sum(len(s.triangles) for s in surfaces),
                      solids=len(surfaces), size=size, gmsh_size=gmsh_size,
                      gmsh_size_note=note, rows=rows)


# ------------------------------------------------------------------------------------------
# output: text table, JSON, histograms
# ------------------------------------------------------------------------------------------

def row_label(row):
    return {OURS: "FemBspTet", OURS_NATIVE: "bsptet_mesh (C++ core)"}.get(
        row.mesher, row.command.split(" (")[0])


def row_dict(row: Row) -> dict:
    """``row`` as a JSON-ready dict without the histogram (the FreeCAD object keeps this)."""
    d = dataclasses.asdict(row)
    d.pop("dihedral_histogram")
    d["steiner_points"] = row.steiner_points
    return d


def row_from_stats(stats, command="fembsptet") -> Row:
    """Our row from the stats of a run made in this process (``core.tetrahedralize`` and the
    CLI's ``seconds_total``): the mesh was checked exactly against the input before it was
    returned, and its boundary has no Steiner point unless allowed."""
    boundary = int(stats.get("boundary_steiner_points") or 0)
    return Row(mesher=OURS, command=command, nodes=int(stats["points"]), tets=int(stats["tets"]),
               steiner_interior=int(stats["steiner_points"]) - boundary,
               steiner_boundary=boundary, min_dihedral_deg=stats.get("min_dihedral_deg"),
               p1_dihedral_deg=stats.get("p1_dihedral_deg"),
               median_dihedral_deg=stats.get("median_dihedral_deg"),
               max_radius_edge_ratio=stats.get("max_radius_edge_ratio"),
               seconds=stats.get("seconds_total"), valid=bool(stats.get("valid")),
               checks=CHECKS_AGAINST_INPUT if not boundary else CHECKS_AGAINST_OWN_BOUNDARY)


def format_rows(rows, keys=None) -> str:
    """``rows`` as a text table, one line per mesher, the columns ``keys`` (default all)."""
    columns = [c for c in COLUMNS if keys is None or c[0] in keys]
    heads = ["mesher"] + [h for _k, h, _f in columns]
    body = [[row_label(r)] + [r.cell(k) for k, _h, _f in columns] for r in rows]
    widths = [max(len(x) for x in col) for col in zip(heads, *body)]
    fmt_row = "  ".join(("{:<%d}" if i == 0 else "{:>%d}") % w for i, w in enumerate(widths))
    lines = [fmt_row.format(*heads)] + [fmt_row.format(*b) for b in body]
    for r in rows:
        if r.status != "ok":
            lines.append(f"{row_label(r)}: {r.status}: {r.message}")
    return "\n".join(lines)


def format_table(result: Comparison) -> str:
    """The comparison as a text table, with the notes it needs to be read."""
    lines = [f"{result.source}: {result.input_points} points, {result.input_triangles} "
             f"triangles, {result.solids} solid(s); size: "
             + ("none (default meshes)" if result.size is None else f"{result.size:g}"),
             format_rows(result.rows)]
    for r in result.rows:
        if r.status != "ok":
            lines.append(f"{row_label(r)}: {r.status}: {r.message}")
    gmsh = result.row(GMSH)
    if gmsh is not None:
        lines.append(f"gmsh: {gmsh.command}; size: {result.gmsh_size_note}")
    for r in result.rows:
        if r.status == "ok":
            lines.append(f"valid ({row_label(r)}): {r.checks}"
                         + ("" if r.valid else "; " + "; ".join(r.check_messages[:2])))
    lines.append("seconds and peak MB: each mesher's own process (start-up included)")
    return "\n".join(lines)


def write_json(path, result: Comparison):

    with atomic_output(path) as f:
        json.dump(result.to_dict(), f, indent=1)


#: Colour of each mesher in the plots.
COLORS = {OURS: "tab:blue", OURS_NATIVE: "tab:purple", TETGEN_PY: "tab:red", TETGEN_PQ: "tab:orange", GMSH: "tab:green"}


def draw_histograms(ax, rows, legend=True, bin_width=5):
    """Dihedral-angle histograms of ``rows`` (fraction of angles per ``bin_width`` degrees,
    summed from the 1-degree bins) as step lines."""
    edges = np.arange(0, 181, bin_width)
    for r in rows:
        if r.status != "ok" or not r.dihedral_histogram:
            continue
        h = np.asarray(r.dihedral_histogram, float)
        h = np.add.reduceat(h, np.arange(0, 180, bin_width))
        ax.step(edges[:-1], h / max(h.sum(), 1), where="post", color=COLORS.get(r.mesher),
                lw=1, label=f"{row_label(r)} (min {r.min_dihedral_deg:.1f})")
    ax.set_xlim(0, 180)
    ax.tick_params(labelsize=7)
    if legend:
        ax.legend(fontsize=6)


def plot_histograms(path, result: Comparison):
    """Writes the dihedral-angle histograms side by side (one panel per mesher) to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt


    rows = [r for r in result.rows if r.status == "ok"]
    fig, axes = plt.subplots(1, max(len(rows), 1), figsize=(3.2 * max(len(rows), 1), 2.6),
                             squeeze=False)  # each panel its own scale: both stay readable
    for ax, r in zip(axes[0], rows):
        h = np.asarray(r.dihedral_histogram, float)
        ax.bar(np.arange(180) + 0.5, h / max(h.sum(), 1), width=1.0,
               color=COLORS.get(r.mesher))
        ax.set_title(f"{row_label(r)}\nmin {r.min_dihedral_deg:.2f}°, {r.tets} tets",
                     fontsize=8)
        ax.set_xlim(0, 180)
        ax.set_xlabel("dihedral angle (deg)", fontsize=7)
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel("fraction of angles", fontsize=7)
    fig.suptitle(os.path.basename(result.source) or "comparison", fontsize=9)
    fig.tight_layout()
    with atomic_output(path, "wb") as f:
        fig.savefig(f, format="png", dpi=80)
    plt.close(fig)
