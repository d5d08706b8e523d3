#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Our mesher against FreeCAD's Gmsh mesher and Netgen on CAD parts: tets, quality, validity,
distance to the CAD, whole-process time and peak memory. Usage:

    bench/fem_vs_peers.py [PART ...] [--divisions D ...] [--order 1|2] [--timeout S]
                          [--meshers ours gmsh netgen] [--distance-sample N]
                          [--ours-args ARGS]
                          [--out-dir DIR] [--json FILE] [--workdir DIR]

PART: STEP/BREP/IGES files or folders of them (default: every CAD file of the public CAD
corpus folder, CORPUS_DIR below, plus resources/samples/bracket.step). For each part and each D
(default 20 40), h = bounding-box diagonal / D, and each mesher runs as its own process with a
time limit:

* ours:   bin/fembsptet mesh PART --size h --order 2 -o OUT.vtu (see ours_command),
* gmsh:   FreeCAD 0.20.2's FemMeshGmsh object (ObjectsFem.makeMeshGmsh, CharacteristicLengthMax h,
          ElementOrder 2nd, GmshTools.create_mesh), headless in /usr/bin/python3, written as .inp,
* netgen: python3-netgen's OCC geometry (LoadOCCGeometry), MeshingParameters(maxh=h),
          Mesh.SecondOrder(), written as .vtu.

Every mesh is then read with meshio and measured by the same code (mesh_measures). Writes
DIR/fem-vs-peers.md, DIR/fem-vs-peers-histograms.png and DIR/fem-vs-peers-bracket.png (DIR default
docs/benchmarks); progress goes to stderr; Ctrl-C stops the running mesher and prints what is done.
"""

import argparse
import datetime
import json
import os
import platform
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PYTHON = "/usr/bin/python3"  # Debian's: FreeCAD's module loads only there
OURS_CLI = os.path.join("bin", "fembsptet")  # relative to ROOT
CORPUS_DIR = os.path.join(os.path.dirname(ROOT), "shared", "data", "corpus", "cad")  # beside the checkout
BRACKET = os.path.join(ROOT, "resources", "samples", "bracket.step")
CAD_EXTENSIONS = (".step", ".stp", ".brep", ".brp", ".iges", ".igs")
MESHERS = ("ours", "gmsh", "netgen")
REPORT_STEM = "fem-vs-peers"
FREECAD_LIB = "/usr/lib/freecad-python3/lib"
FREECAD_MOD = "/usr/share/freecad/Mod"
FREECAD_EXT = "/usr/share/freecad/Ext"

# --- tet10 conventions -------------------------------------------------------------------------
# VTK / meshio / Abaqus C3D10 / SMESH node order: corners 0..3, then mid-nodes of the edges
# (0,1) (1,2) (0,2) (0,3) (1,3) (2,3).
TET10_EDGES = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))
# The same tet with corners 1 and 2 swapped (the other orientation), mid-nodes following.
TET10_FLIP = np.array([0, 2, 1, 3, 6, 5, 4, 7, 9, 8])
# Faces of a positively oriented tet (det[v1-v0, v2-v0, v3-v0] > 0), outward, face k opposite
# corner k.
TET_FACES = np.array([(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)])
# The two faces (opposite corners k, l) meeting at each edge (i, j), in TET10_EDGES order.
EDGE_FACE_PAIRS = ((2, 3), (0, 3), (1, 3), (1, 2), (0, 2), (0, 1))
_GAUSS_A, _GAUSS_B = 0.5854101966249685, 0.1381966011250105  # 4-point rule, degree 2


def tet10_check_points():
    """Barycentric coordinates where tet10 Jacobians are checked: 4 corners, 6 mid-nodes and the
    4 points of the 4-point Gauss rule (14 rows of 4)."""
    corners = np.eye(4)
    mids = np.array([(corners[i] + corners[j]) / 2 for i, j in TET10_EDGES])
    gauss = np.full((4, 4), _GAUSS_B) + np.eye(4) * (_GAUSS_A - _GAUSS_B)
    return np.vstack([corners, mids, gauss])


# --- running one process, measured ------------------------------------------------------------

class Run:
    """What one mesher process did: ok, seconds, cpu seconds, peak bytes, message."""

    def __init__(self, ok, seconds, cpu_seconds, peak_bytes, returncode, message):
        self.ok, self.seconds, self.cpu_seconds = ok, seconds, cpu_seconds
        self.peak_bytes, self.returncode, self.message = peak_bytes, returncode, message


def portable(message):
    """A message without the folders of absolute paths (the part's folder, temporary folders):
    the report names files, not the machine it ran on."""
    return re.sub(r"(?<![\w.])(?:/[^\s/:'\"]+)+/(?=[^\s/])", "", message)


def session_rss_bytes(sid):
    """Resident bytes of every live process of session sid (the process tree of one run)."""
    total = 0
    page = os.sysconf("SC_PAGE_SIZE")
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % name) as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[3]) == sid:  # fields after the name: state ppid pgrp session ...
            total += int(fields[21]) * page  # rss, in pages
    return total


def last_line(path):
    """The last non-empty line of a text file ('' if none)."""
    try:
        with open(path, errors="replace") as f:
            lines = [ln.strip() for ln in f if ln.strip()]
    except OSError:
        return ""
    return lines[-1] if lines else ""


def kill_session(pid):
    """SIGKILL the process group we started (start_new_session: group id == pid)."""
    try:
        os.killpg(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def run_measured(cmd, timeout, log_stem, env=None):
    """Run cmd in its own session; wall seconds, cpu seconds and peak memory of its process tree
    (the larger of the biggest single process and the sampled sum of the tree).
    stdout/stderr go to log_stem.out/.err. Ctrl-C kills the tree and propagates.
    The biggest single process comes from GNU time (%M, the command's own peak RSS, its
    waited-for children included), not from our wait4: the child we fork carries this script's
    pages until it execs, so its ru_maxrss is at least our own size (about 200 MB with numpy,
    meshio and the measured meshes loaded), whatever it runs."""
    err_path = log_stem + ".err"
    maxrss_path = log_stem + ".maxrss"
    cmd = ["/usr/bin/time", "-f", "%M", "-o", maxrss_path] + list(cmd)
    with open(log_stem + ".out", "wb") as out, open(err_path, "wb") as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=out, stderr=err, env=env,
                                start_new_session=True)
    done = {}

    def reap():
        _, status, usage = os.wait4(proc.pid, 0)
        done.update(t=time.perf_counter(), status=status, usage=usage)

    waiter = threading.Thread(target=reap, daemon=True)
    waiter.start()
    sampled, timed_out = 0, False
    try:
        while waiter.is_alive():
            sampled = max(sampled, session_rss_bytes(proc.pid))
            waiter.join(0.05)
            if waiter.is_alive() and time.perf_counter() - t0 > timeout:
                timed_out = True
                kill_session(proc.pid)
                waiter.join()
    except KeyboardInterrupt:
        kill_session(proc.pid)
        waiter.join()
        raise
    proc.returncode = os.waitstatus_to_exitcode(done["status"])
    usage = done["usage"]
    try:
        with open(maxrss_path) as f:
            own_peak = int(f.read().split()[-1]) * 1024  # KB
    except (OSError, ValueError, IndexError):  # killed at the time limit: no report
        own_peak = 0
    peak = max(sampled, own_peak)
    seconds = done["t"] - t0
    cpu = usage.ru_utime + usage.ru_stime
    if timed_out:  # the killed grandchildren's cpu time is lost (never reaped by their parent)
        return Run(False, seconds, None, peak, proc.returncode, "stopped after %g s" % timeout)
    message = "" if proc.returncode == 0 else (last_line(err_path) or
                                               "exit %d, no message" % proc.returncode)
    return Run(proc.returncode == 0, seconds, cpu, peak, proc.returncode, message)


# --- the three meshers' commands ----------------------------------------------------------------

def number_arg(x):
    """A float as a command-line argument, exactly (a string is passed through)."""
    return x if isinstance(x, str) else repr(float(x))


def ours_command(part, h, order, out, extra=()):
    """Our CLI (its flags may change: this is the only place that knows them); extra: more
    flags (--ours-args)."""
    return [os.path.join(ROOT, OURS_CLI), "mesh", part, "--size", number_arg(h), "--order",
            str(order), "-o", out] + list(extra)


def worker_command(mesher, part, h, order, out):
    """This script as a worker process running one peer mesher."""
    return [PYTHON, os.path.abspath(__file__), "--worker", mesher, part, number_arg(h), str(order),
            out]


def mesher_command(mesher, part, h, order, out, ours_extra=()):
    if mesher == "ours":
        return ours_command(part, h, order, out, ours_extra)
    return worker_command(mesher, part, h, order, out)


MESH_EXTENSION = {"ours": ".vtu", "gmsh": ".inp", "netgen": ".vtu"}


# --- workers (run in their own /usr/bin/python3 process) ----------------------------------------

def boot_freecad():
    """Import FreeCAD headless in Debian's python and run the workbenches' Init.py as FreeCAD's
    start-up does (design/freecad.md section 1); console messages on."""
    sys.path.append(FREECAD_LIB)
    import FreeCAD

    mods = sorted(os.path.join(FREECAD_MOD, d) for d in os.listdir(FREECAD_MOD)
                  if os.path.isdir(os.path.join(FREECAD_MOD, d)))
    sys.path.extend(mods + [FREECAD_EXT])
    for d in mods:
        init = os.path.join(d, "Init.py")
        if os.path.isfile(init):
            with open(init, encoding="utf-8") as f:
                code = compile(f.read(), init, "exec")
            try:
                exec(code, {"__file__": init, "__name__": "FreeCADInit", "FreeCAD": FreeCAD,
                            "App": FreeCAD})
            except Exception as e:  # a workbench needing the GUI or a missing dependency
                print("Init of %s failed: %s" % (d, e), file=sys.stderr)
    for kind in ("Msg", "Wrn", "Err"):
        FreeCAD.Console.SetStatus("Console", kind, True)
    return FreeCAD


def write_sidecar(out, info):
    with open(out + ".json", "w") as f:
        json.dump(info, f)


def worker_gmsh(part, h, order, out):
    """FreeCAD's Gmsh mesher as a user gets it: a FemMeshGmsh object, GmshTools.create_mesh."""
    FreeCAD = boot_freecad()
    import ObjectsFem
    import Part
    from femmesh.gmshtools import GmshTools

    doc = FreeCAD.newDocument("bench")
    feature = doc.addObject("Part::Feature", "Part")
    feature.Shape = Part.read(part)
    mesh_obj = ObjectsFem.makeMeshGmsh(doc, "MeshGmsh")
    setattr(mesh_obj, "Shape" if "Shape" in mesh_obj.PropertiesList else "Part", feature)  # 1.x: Shape
    mesh_obj.CharacteristicLengthMax = h
    mesh_obj.ElementOrder = "2nd" if order == 2 else "1st"
    doc.recompute()
    t0 = time.perf_counter()
    error = GmshTools(mesh_obj).create_mesh()
    seconds = time.perf_counter() - t0
    if error:
        sys.exit("gmsh: " + " ".join(str(error).split())[-300:])
    femmesh = mesh_obj.FemMesh
    if femmesh.VolumeCount == 0:
        sys.exit("gmsh: no volume elements (%d faces)" % femmesh.FaceCount)
    femmesh.write(out)
    settings = {p: str(getattr(mesh_obj, p)) for p in (
        "CharacteristicLengthMax", "CharacteristicLengthMin", "ElementOrder", "Algorithm2D",
        "Algorithm3D", "OptimizeStd", "OptimizeNetgen", "HighOrderOptimize",
        "MeshSizeFromCurvature", "SecondOrderLinear") if hasattr(mesh_obj, p)}
    write_sidecar(out, {"mesher_seconds": seconds, "settings": settings})


def worker_netgen(part, h, order, out):
    """python3-netgen on the part at maxh = h, second order when asked
    (FemBspTet.peers.netgen.mesh_with_netgen: the same Netgen run as the task panel's)."""
    import meshio

    sys.path.insert(0, ROOT)
    from FemBspTet.peers.netgen import mesh_with_netgen

    points, tets, seconds, settings = mesh_with_netgen(part, h, order)
    meshio.write(out, meshio.Mesh(points, [("tetra10" if order == 2 else "tetra", tets)]))
    write_sidecar(out, {"mesher_seconds": seconds, "settings": settings})


def run_worker(argv):
    mesher, part, h, order, out = argv[0], argv[1], float(argv[2]), int(argv[3]), argv[4]
    {"gmsh": worker_gmsh, "netgen": worker_netgen}[mesher](part, h, order, out)


# --- reading and measuring a mesh (the same code for every mesher) -------------------------------

def read_tets(path):
    """(points float64 (n,3), tets int (m,4) or (m,10) in VTK order) of a mesh file, via meshio."""
    import meshio

    mesh = meshio.read(path)
    blocks = [c.data for c in mesh.cells if c.type in ("tetra10", "tetra")]
    if not blocks:
        raise ValueError("no tetrahedra in %s" % path)
    widths = {b.shape[1] for b in blocks}
    if len(widths) > 1:
        raise ValueError("mixed tet4 and tet10 in %s" % path)
    return np.asarray(mesh.points, dtype=float), np.vstack(blocks).astype(np.int64)


def corner_volumes6(points, tets):
    """Six times the signed volume of each corner tet."""
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)


def orient_positive(points, tets):
    """Tets in the orientation whose total signed volume is positive (Gmsh's .inp, VTK: positive;
    SMESH and Netgen: negative). Returns (tets, flipped)."""
    if corner_volumes6(points, tets).sum() >= 0:
        return tets, False
    perm = TET10_FLIP[:tets.shape[1]] if tets.shape[1] == 10 else np.array([0, 2, 1, 3])
    return tets[:, perm], True


def dihedral_angles(points, tets):
    """The 6 dihedral angles (degrees) of each corner tet, in TET10_EDGES order; either
    orientation; a degenerate face gives 0."""
    p = points[tets[:, :4]]
    normals = np.stack([np.cross(p[:, f[1]] - p[:, f[0]], p[:, f[2]] - p[:, f[0]])
                        for f in TET_FACES], axis=1)
    length = np.linalg.norm(normals, axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = normals / length[:, :, None]
        cosines = np.stack([-np.einsum("ij,ij->i", unit[:, k], unit[:, m])
                            for k, m in EDGE_FACE_PAIRS], axis=1)
    angles = np.degrees(np.arccos(np.clip(cosines, -1.0, 1.0)))
    return np.nan_to_num(angles, nan=0.0)


def worst_dihedral(points, tets):
    """Each corner tet's smallest dihedral angle (degrees)."""
    return dihedral_angles(points, tets).min(axis=1)


def tet10_shape_gradients(bary):
    """d N_a / d(xi, eta, zeta) of the 10 quadratic shape functions at barycentric point bary
    (VTK order; L0 = 1 - xi - eta - zeta): a (10, 3) array."""
    grad_l = np.array([[-1.0, -1.0, -1.0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    rows = [(4 * bary[i] - 1) * grad_l[i] for i in range(4)]
    rows += [4 * (bary[i] * grad_l[j] + bary[j] * grad_l[i]) for i, j in TET10_EDGES]
    return np.array(rows)


def jacobian_determinants(points, tets):
    """Jacobian determinants per element: tet10 at the 14 tet10_check_points (m, 14); tet4 the
    corner tet's (m, 1). The reference tet's volume is 1/6, so a straight tet gives 6 V."""
    if tets.shape[1] == 4:
        return corner_volumes6(points, tets)[:, None]
    x = points[tets]  # (m, 10, 3)
    dets = [np.linalg.det(np.einsum("mac,ak->mck", x, tet10_shape_gradients(b)))
            for b in tet10_check_points()]
    return np.stack(dets, axis=1)


def count_nonpositive_jacobians(points, tets):
    """Elements with a non-positive Jacobian determinant at any checked point."""
    return int((jacobian_determinants(points, tets) <= 0).any(axis=1).sum())


def boundary_faces(tets):
    """(local face rows, element ids) of the corner faces that belong to one tet only."""
    faces = tets[:, TET_FACES].reshape(-1, 3)  # row 4 e + k: face k of element e
    _, first, counts = np.unique(np.sort(faces, axis=1), axis=0, return_index=True,
                                 return_counts=True)
    once = first[counts == 1]
    return once % 4, once // 4


def smallest_wedge(points, tets):
    """The smallest angle (degrees), inside the solid, between two boundary faces along a common
    edge. Every tet at that edge has a dihedral angle there no larger, so no mesh of this surface
    has a larger worst angle; where the CAD's faces themselves meet at that angle, no mesh of the
    part does. None when no boundary edge has exactly two boundary faces."""
    local, elements = boundary_faces(tets)
    if len(local) == 0:
        return None
    tri = tets[elements[:, None], TET_FACES[local]]
    opposite_local = np.array([sorted(set(range(4)) - set(f))[0] for f in TET_FACES])
    opposite = points[tets[elements, opposite_local[local]]]
    a, b, c = (points[tri[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    normal[np.einsum("ij,ij->i", normal, opposite - a) > 0] *= -1  # outward
    length = np.linalg.norm(normal, axis=1)
    normal = normal / np.where(length > 0, length, 1)[:, None]
    edges, owner, third = [], [], []
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        edges.append(np.sort(tri[:, [i, j]], axis=1))
        owner.append(np.arange(len(tri)))
        third.append(tri[:, k])
    edges, owner, third = np.vstack(edges), np.concatenate(owner), np.concatenate(third)
    _, inverse, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    keep = counts[inverse] == 2
    order = np.argsort(inverse[keep], kind="stable")
    f, t, e = owner[keep][order], third[keep][order], edges[keep][order]
    f1, f2, t2, e0 = f[0::2], f[1::2], t[1::2], e[0::2, 0]
    if len(f1) == 0:
        return None
    between = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", normal[f1], normal[f2]), -1, 1)))
    convex = np.einsum("ij,ij->i", points[t2] - points[e0], normal[f1]) <= 0
    inside = np.where(convex, 180 - between, 180 + between)
    return float(inside.min())


def boundary_nodes(tets):
    """Node ids on the boundary: corners of boundary faces and, for tet10, their mid-nodes."""
    local, elements = boundary_faces(tets)
    ids = [tets[elements[:, None], TET_FACES[local]]]
    if tets.shape[1] == 10:
        edge_mid = {frozenset(e): 4 + k for k, e in enumerate(TET10_EDGES)}
        for a, b in ((0, 1), (1, 2), (2, 0)):
            mid = np.array([edge_mid[frozenset((f[a], f[b]))] for f in TET_FACES])
            ids.append(tets[elements, mid[local]][:, None])
    return np.unique(np.hstack(ids))


def midnode_offset(points, tets):
    """Largest distance of a mid-node from its straight edge's midpoint, over the edge length:
    about 0 for straight elements, small for curved ones; above 0.5 means the node order is
    wrong. None for tet4."""
    if tets.shape[1] != 10:
        return None
    worst = 0.0
    for k, (i, j) in enumerate(TET10_EDGES):
        a, b, m = points[tets[:, i]], points[tets[:, j]], points[tets[:, 4 + k]]
        length = np.linalg.norm(b - a, axis=1)
        worst = max(worst, float(np.max(np.linalg.norm(m - (a + b) / 2, axis=1) /
                                        np.maximum(length, 1e-300))))
    return worst


class CadDistance:
    """Distance from points to the faces of a Part shape (not to the solid: a point inside a
    solid is at 0 from it). Faces whose bounding box is farther than the best so far are
    skipped."""

    def __init__(self, shape):
        import Part

        self.part = Part
        self.faces = list(shape.Faces)
        self.boxes = np.array([(f.BoundBox.XMin, f.BoundBox.YMin, f.BoundBox.ZMin,
                                f.BoundBox.XMax, f.BoundBox.YMax, f.BoundBox.ZMax)
                               for f in self.faces]).reshape(-1, 6)

    def __call__(self, point):
        import FreeCAD

        gap = np.maximum(np.maximum(self.boxes[:, :3] - point, point - self.boxes[:, 3:]), 0)
        lower = np.linalg.norm(gap, axis=1)
        vertex = self.part.Vertex(FreeCAD.Vector(*map(float, point)))
        best = np.inf
        for k in np.argsort(lower):
            if lower[k] >= best:
                break
            best = min(best, self.faces[k].distToShape(vertex)[0])
        return float(best)


def max_distance_to_cad(points, node_ids, cad, sample, seed=0):
    """(largest distance of the given nodes to the CAD, how many nodes were measured): all of
    them, or a random sample of `sample` (0: all)."""
    ids = np.asarray(node_ids)
    if sample and len(ids) > sample:
        ids = np.random.default_rng(seed).choice(ids, sample, replace=False)
    if len(ids) == 0:
        return None, 0
    return max(cad(points[i]) for i in ids), len(ids)


def mesh_measures(path, cad, sample):
    """Everything measured on one mesh file (the per-tet worst dihedral angles under 'worst')."""
    points, tets = read_tets(path)
    tets, flipped = orient_positive(points, tets)
    worst = worst_dihedral(points, tets)
    nodes = boundary_nodes(tets)
    distance, measured = max_distance_to_cad(points, nodes, cad, sample) if cad else (None, 0)
    return {"tets": len(tets), "nodes": int(len(np.unique(tets))),
            "order": 2 if tets.shape[1] == 10 else 1, "negative_convention": flipped,
            "min_dihedral": float(worst.min()), "p1_dihedral": float(np.percentile(worst, 1)),
            "median_dihedral": float(np.median(worst)),
            "share_under_10": float(np.mean(worst < 10.0)),
            "bad_jacobian": count_nonpositive_jacobians(points, tets),
            "boundary_nodes": int(len(nodes)), "distance_nodes": measured,
            "max_distance": distance, "midnode_offset": midnode_offset(points, tets),
            "smallest_wedge": smallest_wedge(points, tets[:, :4]), "worst": worst}


# --- the benchmark ------------------------------------------------------------------------------

def part_paths(inputs):
    """CAD files named, or found in the folders named, in order, without repeats."""
    found = []
    for item in inputs:
        if os.path.isdir(item):
            found += sorted(os.path.join(item, f) for f in os.listdir(item)
                            if f.lower().endswith(CAD_EXTENSIONS))
        else:
            found.append(item)
    seen, paths = set(), []
    for p in map(os.path.abspath, found):
        if p not in seen:
            seen.add(p)
            paths.append(p)
    return paths


def netgen_input(part, shape, workdir):
    """A file LoadOCCGeometry reads: Netgen 6.2.1905 reads STEP and IGES but takes any other file
    (BREP) for STEP, so BREP parts are exported to STEP first (outside the timed run)."""
    if part.lower().endswith((".step", ".stp", ".iges", ".igs")):
        return part
    step = os.path.join(workdir, os.path.splitext(os.path.basename(part))[0] + ".step")
    if not os.path.exists(step):
        shape.exportStep(step)
    return step


def progress(msg):
    print("[%s] %s" % (time.strftime("%H:%M:%S"), msg), file=sys.stderr, flush=True)


def run_one(mesher, run_input, h, args, workdir, stem, cad):
    """One mesher on one part at one h: the run, then the measures (a flat dict)."""
    out = os.path.join(workdir, stem + "-" + mesher + MESH_EXTENSION[mesher])
    env = dict(os.environ, TMPDIR=workdir)  # GmshTools' scratch folders land in workdir
    cmd = mesher_command(mesher, run_input, h, args.order, out, shlex.split(args.ours_args))
    run = run_measured(cmd, args.timeout, os.path.join(workdir, stem + "-" + mesher), env=env)
    row = {"mesher": mesher, "ok": run.ok, "message": run.message, "seconds": run.seconds,
           "cpu_seconds": run.cpu_seconds, "peak_mb": run.peak_bytes / 1e6, "mesh": out}
    if run.ok and not os.path.isfile(out):
        row.update(ok=False, message="exit 0 but no mesh file was written")
    if os.path.isfile(out + ".json"):
        with open(out + ".json") as f:
            row.update(json.load(f))
    if row["ok"]:
        try:
            row.update(mesh_measures(out, cad, args.distance_sample))
        except Exception as e:  # an unreadable mesh is that mesher's failure
            row.update(ok=False, message="mesh not readable: %s: %s" % (type(e).__name__, e))
    return row


def describe(row):
    if not row["ok"]:
        return "FAILED (%s) after %.1f s" % (row["message"], row["seconds"])
    return "%d tets, %.1f s, %.0f MB, min %.1f deg, bad J %d" % (
        row["tets"], row["seconds"], row["peak_mb"], row["min_dihedral"], row["bad_jacobian"])


def benchmark(args, workdir, results):
    """Run every part x D x mesher; append each case ({part, D, h, rows}) to results."""
    FreeCAD = import_freecad()
    import Part

    parts = part_paths(args.parts)
    for n, part in enumerate(parts, 1):
        name = os.path.basename(part)
        try:
            shape = Part.read(part)
        except Exception as e:
            progress("%s: not readable by FreeCAD: %s" % (name, e))
            results.append({"part": name, "path": part, "unreadable": str(e), "cases": []})
            continue
        diagonal = shape.BoundBox.DiagonalLength
        cad = CadDistance(shape)
        entry = {"part": name, "path": part, "diagonal": diagonal, "faces": len(shape.Faces),
                 "solids": len(shape.Solids), "cases": []}
        results.append(entry)
        for d in args.divisions:
            h = diagonal / d
            case = {"D": d, "h": h, "rows": {}}
            entry["cases"].append(case)
            stem = "%02d-%s-D%g" % (n, os.path.splitext(name)[0], d)
            for mesher in args.meshers:
                run_input = netgen_input(part, shape, workdir) if mesher == "netgen" else part
                progress("[%d/%d] %s D=%g h=%.4g: %s ..." % (n, len(parts), name, d, h, mesher))
                row = run_one(mesher, run_input, h, args, workdir, stem, cad)
                case["rows"][mesher] = row
                progress("[%d/%d] %s D=%g: %s %s" % (n, len(parts), name, d, mesher,
                                                      describe(row)))
            print_case(entry, case, args.meshers)
    return FreeCAD


def import_freecad():
    """FreeCAD in this (main) process, for reading parts and measuring CAD distances."""
    if "FreeCAD" in sys.modules:
        return sys.modules["FreeCAD"]
    sys.path.append(FREECAD_LIB)
    import FreeCAD

    return FreeCAD


# --- tables ---------------------------------------------------------------------------------------

COLUMNS = ("mesher", "result", "tets", "nodes", "s", "cpu s", "peak MB", "min°", "1%°", "median°",
           "<10°", "bad J", "max dist", "dist nodes")


def fmt(value, spec):
    return "–" if value is None else format(value, spec)


def row_cells(row):
    if not row["ok"]:
        return [row["mesher"], "failed: " + portable(row["message"])[:160], "", "",
                fmt(row["seconds"], ".1f"), fmt(row["cpu_seconds"], ".1f"),
                fmt(row["peak_mb"], ".0f")] + [""] * 7
    return [row["mesher"], "ok", str(row["tets"]), str(row["nodes"]), fmt(row["seconds"], ".1f"),
            fmt(row["cpu_seconds"], ".1f"), fmt(row["peak_mb"], ".0f"),
            fmt(row["min_dihedral"], ".2f"), fmt(row["p1_dihedral"], ".1f"),
            fmt(row["median_dihedral"], ".1f"), fmt(100 * row["share_under_10"], ".2f") + "%",
            str(row["bad_jacobian"]), fmt(row["max_distance"], ".2e"),
            "%d/%d" % (row["distance_nodes"], row["boundary_nodes"])]


RATIO_KEYS = (("tets", "tets"), ("seconds", "s"), ("peak_mb", "peak MB"))


def ratios(case, peer):
    """{key: ours / peer} for tets, seconds and peak memory, if both ran."""
    ours, other = case["rows"].get("ours"), case["rows"].get(peer)
    if not (ours and other and ours["ok"] and other["ok"]):
        return None
    return {k: ours[k] / other[k] if other[k] else None for k, _ in RATIO_KEYS}


def ratio_text(case, peer):
    r = ratios(case, peer)
    if r is None:
        return "ours/%s: –" % peer
    return "ours/%s: " % peer + ", ".join("%s %s" % (label, fmt(r[k], ".2f"))
                                         for k, label in RATIO_KEYS)


def print_case(entry, case, meshers):
    print("\n%s  D=%g  h=%.4g" % (entry["part"], case["D"], case["h"]))
    widths = [8, 34, 8, 8, 7, 7, 8, 6, 6, 8, 7, 6, 9, 10]
    print(" ".join(c.ljust(w) for c, w in zip(COLUMNS, widths)))
    for m in meshers:
        cells = row_cells(case["rows"][m])
        print(" ".join(c[:max(w, 1) if i == 1 else None].ljust(w)
                       for i, (c, w) in enumerate(zip(cells, widths))))
    print("  " + "; ".join(ratio_text(case, p) for p in ("gmsh", "netgen") if p in meshers),
          flush=True)


def median_ratios(results, divisions, peer):
    """{D: ({key: median ratio}, number of parts)} over the parts where ours and peer both ran."""
    out = {}
    for d in divisions:
        rs = [ratios(c, peer) for e in results for c in e["cases"] if c["D"] == d]
        rs = [r for r in rs if r]
        out[d] = ({k: float(np.median([r[k] for r in rs if r[k] is not None])) if rs else None
                   for k, _ in RATIO_KEYS}, len(rs))
    return out


def mesher_medians(results, divisions, meshers):
    """{(D, mesher): (successes, attempts, median min dihedral, median 1% dihedral,
    median of the per-tet median, meshes with a min dihedral of 10 degrees or more,
    parts with a bad Jacobian, median max distance / h)}."""
    out = {}
    for d in divisions:
        for m in meshers:
            cases = [c for e in results for c in e["cases"] if c["D"] == d and m in c["rows"]]
            ok = [c for c in cases if c["rows"][m]["ok"]]
            rows = [c["rows"][m] for c in ok]
            dist = [c["rows"][m]["max_distance"] / c["h"] for c in ok
                    if c["rows"][m]["max_distance"] is not None]
            out[(d, m)] = (len(ok), len(cases),
                           float(np.median([r["min_dihedral"] for r in rows])) if rows else None,
                           float(np.median([r["p1_dihedral"] for r in rows])) if rows else None,
                           float(np.median([r["median_dihedral"] for r in rows])) if rows else None,
                           sum(1 for r in rows if r["min_dihedral"] >= 10),
                           sum(1 for r in rows if r["bad_jacobian"] > 0),
                           float(np.median(dist)) if dist else None)
    return out


def print_summary(results, args):
    print("\nMedians over parts")
    for peer in ("gmsh", "netgen"):
        if peer not in args.meshers or "ours" not in args.meshers:
            continue
        for d, (med, n) in median_ratios(results, args.divisions, peer).items():
            print("  D=%g ours/%s over %d parts: %s" % (d, peer, n, ", ".join(
                "%s %s" % (label, fmt(med[k], ".2f")) for k, label in RATIO_KEYS)))
    for (d, m), (ok, n, mn, p1, md, good, bad, dist) in mesher_medians(
            results, args.divisions, args.meshers).items():
        print("  D=%g %-6s ok %d/%d, median min° %s, median 1%%° %s, median median° %s, "
              "min >= 10° %d/%d, parts with bad J %d, median max dist/h %s"
              % (d, m, ok, n, fmt(mn, ".2f"), fmt(p1, ".1f"), fmt(md, ".2f"), good, ok, bad,
                 fmt(dist, ".2e")))


# --- report and pictures --------------------------------------------------------------------------

def package_version(name):
    try:
        return subprocess.run(["dpkg-query", "-W", "-f=${Version}", name], capture_output=True,
                              text=True, timeout=30).stdout.strip() or "not installed"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def machine_info():
    cpu = "unknown"
    memory = "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
        with open("/proc/meminfo") as f:
            kb = int(next(ln.split()[1] for ln in f if ln.startswith("MemTotal")))
            memory = "%.1f GB" % (kb / 1e6)
    except (OSError, StopIteration):
        pass
    debian = open("/etc/debian_version").read().strip() if os.path.exists(
        "/etc/debian_version") else "?"
    return ("%s, %d cores, %s RAM, Linux %s, Debian %s, Python %s" % (
        cpu, os.cpu_count(), memory, platform.release(), debian, platform.python_version()))


def checkout_state():
    try:
        head = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, timeout=30).stdout.strip()
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=30).stdout.strip()
        return head + (" (with uncommitted changes)" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def versions(freecad):
    v = freecad.Version()
    return {"FreeCAD": "%s.%s.%s (freecad-python3 %s)" % (v[0], v[1], v[2],
                                                         package_version("freecad-python3")),
            "Gmsh": package_version("gmsh"), "Netgen": package_version("python3-netgen"),
            "meshio": package_version("python3-meshio"), "checkout": checkout_state()}


def md_table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c).replace("|", "/") for c in r) + " |" for r in rows]
    return "\n".join(lines)


def peer_settings(results):
    """The settings the peer workers recorded (from the first run of each that has them)."""
    found = {}
    for e in results:
        for c in e["cases"]:
            for m, row in c["rows"].items():
                if m != "ours" and "settings" in row and m not in found:
                    found[m] = row["settings"]
    return found


def report_text(results, args, command, info, ver, started, seconds, pictures):
    out = ["# FemBspTet against FreeCAD's Gmsh mesher and Netgen", "",
           "Generated by `bench/fem_vs_peers.py`; overwritten on every run.", "",
           "* Command: `%s`" % command,
           "* Started %s, took %.0f s" % (started, seconds),
           "* Machine: %s" % info,
           "* Versions: " + ", ".join("%s %s" % kv for kv in ver.items()),
           "* h = bounding-box diagonal / D for D in %s; element order %d; time limit %g s per run"
           % (", ".join("%g" % d for d in args.divisions), args.order, args.timeout), ""]
    out += how_run_section(results, args) + how_measured_section(args)
    out += ["## Results per part", ""]
    for e in results:
        if "unreadable" in e:
            out += ["### %s" % e["part"], "", "FreeCAD cannot read it: %s" % e["unreadable"], ""]
        for c in e["cases"]:
            out += case_section(e, c, args)
    out += summary_markdown(results, args)
    for title, path in pictures:
        out += ["![%s](%s)" % (title, os.path.basename(path)), ""]
    return "\n".join(out) + "\n"


def how_run_section(results, args):
    ours = " ".join(ours_command("PART", "H", args.order, "OUT.vtu",
                                 shlex.split(args.ours_args))).replace(ROOT + "/", "")
    out = ["## How each mesher was run", "",
           "* **ours**: `%s` (whole process: Python start-up, FreeCAD import, tessellation, "
           "meshing, writing)." % ours,
           "* **gmsh**: FreeCAD's Gmsh mesher as a user gets it, headless in /usr/bin/python3: "
           "`ObjectsFem.makeMeshGmsh(doc)`, `Part` = a `Part::Feature` holding "
           "`Part.read(PART)`, `CharacteristicLengthMax = H`, `ElementOrder = '%s'`, every other "
           "property at its default, `doc.recompute()`, "
           "`femmesh.gmshtools.GmshTools(obj).create_mesh()` (writes a .geo, runs the gmsh "
           "binary, reads the .unv back), then `FemMesh.write('OUT.inp')`. The time includes "
           "FreeCAD's start-up." % ("2nd" if args.order == 2 else "1st"),
           "* **netgen**: python3-netgen: `netgen.NgOCC.LoadOCCGeometry(PART)`, "
           "`geo.GenerateMesh(mp=netgen.meshing.MeshingParameters(maxh=H))`%s, nodes and "
           "elements taken through `mesh.Points()` / `mesh.Elements3D()` and written with meshio "
           "(.vtu)." % (", `mesh.SecondOrder()`" if args.order == 2 else ""),
           "  Netgen 6.2.1905's Python OCC meshing takes its local mesh size (edge division, "
           "surface size) from the library's global `netgen::mparam`, not from the "
           "MeshingParameters it is given (fixed upstream after 6.2.1905, NGSolve/netgen pull "
           "request #25): with `maxh` alone a 10 mm cube stays 5 tets at any maxh and the "
           "bracket gives the same 3687 tets for maxh 5 to 1000. So the worker first sets the "
           "global as C++ callers (FreeCAD's and SALOME's Netgen plug-ins) do: nglib's "
           "`Ng_Meshing_Parameters` with maxh = H, elementsperedge 1, elementspercurve 2, "
           "grading 0.3 (the MeshingParameters defaults, FreeCAD's 'Moderate'), then "
           "`Transfer_Parameters()`, called through ctypes (`FemBspTet.peers.netgen`).",
           "  Netgen 6.2.1905 reads only STEP and IGES here (a .brep is parsed as STEP and "
           "refused), so BREP parts are exported to STEP by FreeCAD before the timed run.", ""]
    for m, settings in peer_settings(results).items():
        out.append("Settings recorded by the %s worker: %s" % (m, ", ".join(
            "%s = %s" % kv for kv in settings.items())))
    return out + [""]


def how_measured_section(args):
    sample = ("a random sample of at most %d boundary nodes per mesh (seed 0)" %
              args.distance_sample if args.distance_sample else "all boundary nodes")
    return ["## How the meshes were measured", "",
            "One code reads every mesh with meshio and measures it:",
            "* tets and nodes (nodes used by a tet);",
            "* dihedral angles of each tet's corner tet; per tet the smallest; columns: the "
            "smallest over the mesh (min°), the 1st percentile (1%°), the median, and the share "
            "of tets whose smallest angle is under 10°;",
            "* the smallest angle between two boundary faces along an edge, inside the solid: "
            "every tet at that edge has a dihedral angle there no larger, so it bounds the mesh's "
            "worst angle (where the CAD faces themselves meet at that angle, every mesher's);",
            "* **bad J**: elements with a Jacobian determinant <= 0 at any of the 4 corners, 6 "
            "mid-nodes and 4 Gauss points (4-point rule) of the quadratic map (tet4: the corner "
            "tet's volume). Orientation: a mesh whose total signed volume is negative (SMESH and "
            "Netgen convention) is flipped first, so a consistently oriented valid mesh has "
            "bad J 0;",
            "* **max dist**: the largest distance (model units, mm) from a boundary node (corners "
            "and mid-nodes of faces that belong to one tet) to the CAD faces "
            "(`face.distToShape(Part.Vertex(p))`, faces pruned by bounding box), on %s; "
            "`dist nodes` = measured / boundary nodes;" % sample,
            "* **s**: wall seconds of the whole process; **cpu s**: its user + system seconds "
            "(children included; – for a run stopped at the time limit, whose killed children "
            "are never reaped; FreeCAD's .geo sets gmsh's General.NumThreads to the number of "
            "cores, so gmsh may use more cpu than wall seconds); **peak MB** (10^6 bytes): the "
            "larger of the biggest single process's peak RSS (GNU time's %M) and the sum of the RSS of "
            "the run's process tree sampled every 50 ms (FreeCAD + the gmsh binary are two "
            "processes).", ""]


def case_section(entry, case, args):
    rows = case["rows"]
    out = ["### %s, D = %g (h = %.4g; %d faces, %d solids)" % (
        entry["part"], case["D"], case["h"], entry["faces"], entry["solids"]), "",
        md_table(COLUMNS, [row_cells(rows[m]) for m in args.meshers if m in rows]), "",
        "; ".join(ratio_text(case, p) for p in ("gmsh", "netgen") if p in args.meshers), ""]
    inner = ["%s %.2f s" % (m, r["mesher_seconds"]) for m, r in rows.items()
             if r.get("mesher_seconds") is not None]
    if inner:
        out += ["Meshing alone (inside the worker): " + ", ".join(inner) + ".", ""]
    offsets = {m: r["midnode_offset"] for m, r in rows.items()
               if r.get("midnode_offset") is not None}
    if offsets:
        out += ["Largest mid-node offset from its straight edge's midpoint / edge length "
                "(0: straight elements): " + ", ".join("%s %.3g" % kv for kv in offsets.items())
                + ".", ""]
    wedges = {m: r["smallest_wedge"] for m, r in rows.items()
              if r.get("ok") and r.get("smallest_wedge") is not None}
    if wedges:
        out += ["Smallest angle between two boundary faces along an edge, inside the solid (no tet "
                "at that edge has a larger worst angle): " +
                ", ".join("%s %.2f°" % kv for kv in wedges.items()) + ".", ""]
    odd = [m for m, v in offsets.items() if v > 0.5]
    if odd:
        out += ["Warning: a mid-node of %s lies far from its edge: wrong node order?"
                % ", ".join(odd), ""]
    return out


def summary_markdown(results, args):
    out = ["## Medians over parts", ""]
    rows = []
    for peer in ("gmsh", "netgen"):
        if peer in args.meshers and "ours" in args.meshers:
            for d, (med, n) in median_ratios(results, args.divisions, peer).items():
                rows.append(["ours/%s" % peer, "%g" % d, n] +
                            [fmt(med[k], ".2f") for k, _ in RATIO_KEYS])
    if rows:
        out += [md_table(["ratio", "D", "parts (both ran)", "tets", "seconds", "peak MB"], rows),
                ""]
    rows = [[m, "%g" % d, "%d/%d" % (ok, n), fmt(mn, ".2f"), fmt(p1, ".1f"), fmt(md, ".2f"),
             "%d/%d" % (good, ok), bad, fmt(dist, ".2e")]
            for (d, m), (ok, n, mn, p1, md, good, bad, dist) in mesher_medians(
                results, args.divisions, args.meshers).items()]
    out += [md_table(["mesher", "D", "meshed", "median min°", "median 1%°", "median median°",
                      "min ≥ 10°", "parts with bad J", "median max dist / h"], rows), ""]
    narrow = {}
    for e in results:
        for c in e["cases"]:
            ours = c["rows"].get("ours", {})
            if ours.get("ok") and (ours.get("smallest_wedge") or 180) < 10:
                narrow[e["part"]] = min(narrow.get(e["part"], 180), ours["smallest_wedge"])
    if narrow:
        out += ["Parts where two of our boundary triangles meet inside the solid at under 10° "
                "(every tet at that edge has its worst angle below that; the CAD faces there may "
                "meet at a wider angle than the chords do): " +
                ", ".join("%s (%.2f°)" % kv for kv in sorted(narrow.items())) + ".", ""]
    return out


def plot_histograms(results, args, path):
    """Per-tet worst dihedral angle, pooled over parts, one column per D: distribution and the
    share of tets under each angle."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(args.divisions), figsize=(6 * len(args.divisions), 8),
                             squeeze=False)
    colors = {"ours": "tab:red", "gmsh": "tab:blue", "netgen": "tab:green"}
    for col, d in enumerate(args.divisions):
        for m in args.meshers:
            pooled = [c["rows"][m]["worst"] for e in results for c in e["cases"]
                      if c["D"] == d and m in c["rows"] and c["rows"][m]["ok"]]
            if not pooled:
                continue
            w = np.concatenate(pooled)
            label = "%s (%d parts, %d tets)" % (m, len(pooled), len(w))
            axes[0, col].hist(w, bins=np.arange(0, 91, 1.0), density=True, histtype="step",
                              color=colors[m], label=label)
            xs = np.sort(w)
            axes[1, col].plot(xs, np.arange(1, len(xs) + 1) / len(xs), color=colors[m], label=m)
        axes[0, col].set(title="h = diagonal / %g, order %d" % (d, args.order),
                         xlabel="smallest dihedral angle of a tet (degrees)", ylabel="density")
        axes[1, col].set(xlabel="smallest dihedral angle of a tet (degrees)", xlim=(0, 40),
                         yscale="log", ylabel="share of tets below")
        axes[0, col].legend(fontsize=8)
        axes[1, col].legend(fontsize=8)
        axes[1, col].grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def view_rotation(azimuth=-60.0, elevation=25.0):
    """Rows: screen x, screen y, towards the viewer."""
    a, e = np.radians(azimuth), np.radians(elevation)
    toward = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = np.cross([0.0, 0.0, 1.0], toward)
    right /= np.linalg.norm(right)
    return np.array([right, np.cross(toward, right), toward])


def boundary_polygons(points, tets):
    """Outward boundary faces as polygons (corner, mid, corner, mid, ... for tet10) and their
    corner normals."""
    local, elements = boundary_faces(tets)
    corners = tets[elements[:, None], TET_FACES[local]]
    if tets.shape[1] == 10:
        edge_mid = {frozenset(e): 4 + k for k, e in enumerate(TET10_EDGES)}
        mids = [np.array([edge_mid[frozenset((f[a], f[(a + 1) % 3]))] for f in TET_FACES])
                for a in range(3)]
        ring = np.stack([corners[:, 0], tets[elements, mids[0][local]], corners[:, 1],
                         tets[elements, mids[1][local]], corners[:, 2],
                         tets[elements, mids[2][local]]], axis=1)
    else:
        ring = corners
    p = points[corners]
    normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return ring, normals


def draw_mesh(ax, path, title, rotation):
    """Front-facing boundary faces, painter's order, shaded, edges drawn."""
    from matplotlib.collections import PolyCollection

    points, tets = read_tets(path)
    tets, _ = orient_positive(points, tets)
    ring, normals = boundary_polygons(points, tets)
    facing = normals @ rotation[2]
    keep = facing > 0
    ring, facing = ring[keep], facing[keep] / np.linalg.norm(normals[keep], axis=1)
    screen = points @ rotation.T
    order = np.argsort(screen[ring].mean(axis=1)[:, 2])  # far first
    shade = 0.35 + 0.6 * facing[order]
    polys = PolyCollection(screen[ring[order]][:, :, :2], facecolors=np.outer(shade,
                           [0.75, 0.8, 0.9]), edgecolors="k", linewidths=0.15)
    ax.add_collection(polys)
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(title, fontsize=10)


def plot_bracket(results, args, path):
    """The three meshes of the bracket at D = 20 side by side, same view. False if absent."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    case = next((c for e in results if e["part"] == os.path.basename(BRACKET)
                 for c in e["cases"] if c["D"] == 20), None)
    if case is None:
        return False
    fig, axes = plt.subplots(1, len(args.meshers), figsize=(6 * len(args.meshers), 5.5),
                             squeeze=False)
    rotation = view_rotation()
    for ax, m in zip(axes[0], args.meshers):
        row = case["rows"][m]
        if row["ok"]:
            draw_mesh(ax, row["mesh"], "%s: %d tets, %d nodes" % (m, row["tets"], row["nodes"]),
                      rotation)
        else:
            ax.set_axis_off()
            ax.text(0.5, 0.5, "%s failed:\n%s" % (m, portable(row["message"])[:80]), ha="center",
                    va="center", wrap=True, transform=ax.transAxes)
    fig.suptitle("bracket.step, h = diagonal / 20 = %.3g, order %d (boundary faces; curved "
                 "edges through their mid-nodes)" % (case["h"], args.order))
    fig.tight_layout(rect=(0, 0, 1, 0.94))
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def json_ready(results):
    """The results without the per-tet arrays."""
    return [dict(e, cases=[dict(c, rows={m: {k: v for k, v in r.items() if k != "worst"}
                                         for m, r in c["rows"].items()}) for c in e["cases"]])
            for e in results]


def write_outputs(results, args, command, freecad, started, seconds):
    os.makedirs(args.out_dir, exist_ok=True)
    stem = os.path.join(args.out_dir, REPORT_STEM)
    pictures = []
    plot_histograms(results, args, stem + "-histograms.png")
    pictures.append(("worst dihedral angle per tet, pooled over parts", stem + "-histograms.png"))
    if plot_bracket(results, args, stem + "-bracket.png"):
        pictures.append(("the bracket at h = diagonal / 20", stem + "-bracket.png"))
    text = report_text(results, args, command, machine_info(), versions(freecad), started,
                       seconds, pictures)
    with open(stem + ".md", "w") as f:
        f.write(text)
    progress("wrote %s.md and %d pictures" % (stem, len(pictures)))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(json_ready(results), f, indent=1)


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("parts", nargs="*", default=[CORPUS_DIR, BRACKET],
                    help="CAD files or folders (default: %s and the bracket)" % CORPUS_DIR)
    ap.add_argument("--divisions", type=float, nargs="+", default=[20, 40], metavar="D",
                    help="h = bounding-box diagonal / D (default 20 40)")
    ap.add_argument("--order", type=int, choices=(1, 2), default=2)
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per run (600)")
    ap.add_argument("--meshers", nargs="+", choices=MESHERS, default=list(MESHERS))
    ap.add_argument("--distance-sample", type=int, default=2000, metavar="N",
                    help="boundary nodes measured against the CAD per mesh (0: all; 2000)")
    ap.add_argument("--out-dir", default=os.path.join(ROOT, "docs", "benchmarks"),
                    help="where %s.md and the pictures go" % REPORT_STEM)
    ap.add_argument("--ours-args", default="", metavar="ARGS",
                    help="more flags for our CLI, e.g. --ours-args=--tessellation")
    ap.add_argument("--json", default=None, help="also write the figures here")
    ap.add_argument("--workdir", default=None, help="keep the meshes and logs here")
    args = ap.parse_args(argv)
    args.divisions = [int(d) if d == int(d) else d for d in args.divisions]
    return args


# Options that only name files or folders of this machine: the report's command line leaves them
# out (they change no figure).
MACHINE_PATH_OPTIONS = ("--workdir", "--json", "--out-dir")


def report_argv(argv):
    """The command line as the report gives it, without MACHINE_PATH_OPTIONS and their values."""
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
        elif a in MACHINE_PATH_OPTIONS:
            skip = True
        elif not any(a.startswith(o + "=") for o in MACHINE_PATH_OPTIONS):
            out.append(a)
    return out


def main(argv):
    if argv[:1] == ["--worker"]:
        return run_worker(argv[1:])
    args = parse_args(argv)
    command = "bench/fem_vs_peers.py " + " ".join(shlex.quote(a) for a in report_argv(argv))
    started = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    t0 = time.perf_counter()
    workdir = args.workdir or tempfile.mkdtemp(prefix="fem-vs-peers-")
    os.makedirs(workdir, exist_ok=True)
    results = []
    try:
        freecad = benchmark(args, workdir, results)
        print_summary(results, args)
        write_outputs(results, args, command, freecad, started, time.perf_counter() - t0)
    except KeyboardInterrupt:
        progress("interrupted: the running mesher was stopped; no report written")
        print_summary(results, args)
        return 130
    finally:
        if not args.workdir:
            shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
