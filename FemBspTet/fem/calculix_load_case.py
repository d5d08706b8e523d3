# SPDX-License-Identifier: LGPL-2.1-or-later
"""A linear static CalculiX analysis of a CAD FEM mesh, with no FreeCAD: the solver's own verdict
on the elements (it refuses a tet10 whose Jacobian is not positive at its integration points).

    from FemBspTet.fem.cad_mesh import mesh_cad_file
    from FemBspTet.fem.calculix_load_case import solve_face_load

    result = mesh_cad_file("part.step", order=2)
    figures = solve_face_load(result, "work/")   # InternalError if CalculiX refuses the mesh

The load case, per group of connected solids (solids that share nodes; solids that only touch
have separate nodes and are separate groups): the group's lowest-numbered CAD face fixed (all
nodes, mid-nodes included), and its highest-numbered CAD face pushed inward along its mean
normal with a total force of 1000 N spread equally over its nodes. A group with a single CAD
face (a sphere) is fixed on it and carries its own weight instead. Steel: E = 210000 MPa,
nu = 0.3, density 7.9e-9 t/mm^3. Model units are taken as mm.
"""

import math
import os
import re
import shutil
import subprocess

import numpy as np

from ..errors import InternalError
from ..volume_io import write_tet_mesh

TOTAL_FORCE_N = 1000.0


def _groups_of_solids(tets, tet_solid):
    """Lists of solid ids that share nodes (connected through shared faces), sorted."""
    solids = sorted(set(np.unique(tet_solid).tolist()))
    parent = {s: s for s in solids}

    def find(s):
        while parent[s] != s:
            parent[s] = parent[parent[s]]
            s = parent[s]
        return s

    corners = tets[:, :4]
    node_solid = np.full(int(corners.max()) + 1, -1, dtype=np.int64)
    for s in solids:
        nodes = np.unique(corners[tet_solid == s])
        other = node_solid[nodes]
        for t in np.unique(other[other >= 0]).tolist():
            parent[find(t)] = find(s)
        node_solid[nodes] = s
    groups = {}
    for s in solids:
        groups.setdefault(find(s), []).append(s)
    return sorted(groups.values())


def _face_nodes(result, face):
    """Node ids (0-based) of CAD face `face`: corners and, for tet10, mid-nodes of its triangles."""
    rows = result.boundary.face_tags == face
    nodes = [result.boundary.triangles[rows].ravel()]
    if len(result.boundary_midnodes):
        nodes.append(result.boundary_midnodes[rows].ravel())
    return np.unique(np.concatenate(nodes))


def _mean_outward_normal(result, face):
    tri = result.boundary.triangles[result.boundary.face_tags == face]
    p = result.mesh.points
    n = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]).sum(axis=0)
    length = float(np.linalg.norm(n))
    return n / length if length > 0 else np.array([0.0, 0.0, 1.0])


def _set_lines(name, ids):
    out = [f"*NSET, NSET={name}\n"]
    ids = (np.asarray(ids) + 1).tolist()
    for i in range(0, len(ids), 16):
        out.append(", ".join(str(v) for v in ids[i:i + 16]) + "\n")
    return out


def _read_displacements(dat_path):
    """{node id: (ux, uy, uz)} from CalculiX's .dat (*NODE PRINT, U)."""
    u = {}
    reading = False
    with open(dat_path, errors="replace") as f:
        for line in f:
            if line.strip().startswith("displacements"):
                reading = True
                continue
            if not reading:
                continue
            parts = line.split()
            if len(parts) == 4 and re.fullmatch(r"\d+", parts[0]):
                u[int(parts[0])] = tuple(float(x.replace("D", "E")) for x in parts[1:])
            elif parts and u:
                reading = False
    return u


def solve_face_load(result, workdir, ccx=None, timeout=1800):
    """Writes the mesh and the load case (module doc) into `workdir`, runs CalculiX and returns
    {"groups", "fixed_faces", "loaded_faces", "nodes", "elements", "max_displacement",
    "seconds"}. Raises InternalError with CalculiX's message when it refuses or fails, or when a
    displacement is not finite or a fixed node moved."""
    import time

    ccx = ccx or shutil.which("ccx")
    if ccx is None:
        raise InternalError("CalculiX (ccx) is not installed: apt install calculix-ccx")
    os.makedirs(workdir, exist_ok=True)
    mesh = result.mesh
    order = 2 if mesh.tets.shape[1] == 10 else 1
    write_tet_mesh(os.path.join(workdir, "mesh.inp"), mesh)
    faces_of_solid_nodes = []
    lines = ["*INCLUDE, INPUT=mesh.inp\n"]
    fixed, loaded, gravity = [], [], []
    node_solid = np.full(len(mesh.points), -1, dtype=np.int64)
    for s in np.unique(result.tet_solid).tolist():
        node_solid[np.unique(mesh.tets[result.tet_solid == s])] = s
    for k, group in enumerate(_groups_of_solids(mesh.tets, result.tet_solid)):
        in_group = np.isin(node_solid[result.boundary.triangles[:, 0]], group)
        faces = sorted(set(result.boundary.face_tags[in_group].tolist()))
        if not faces:
            raise InternalError(f"solids {group} have no boundary face")
        fixed.append(faces[0])
        lines += _set_lines(f"FIX{k}", _face_nodes(result, faces[0]))
        if len(faces) > 1:
            loaded.append(faces[-1])
            nodes = _face_nodes(result, faces[-1])
            lines += _set_lines(f"LOAD{k}", nodes)
            faces_of_solid_nodes.append((k, -_mean_outward_normal(result, faces[-1])
                                         * TOTAL_FORCE_N / len(nodes)))
        else:
            lines.append(f"*ELSET, ELSET=BODY{k}\n")
            ids = (np.flatnonzero(np.isin(result.tet_solid, group)) + 1).tolist()
            for i in range(0, len(ids), 16):
                lines.append(", ".join(str(v) for v in ids[i:i + 16]) + "\n")
            gravity.append(k)
    lines += ["*MATERIAL, NAME=STEEL\n", "*ELASTIC\n", "210000, 0.3\n", "*DENSITY\n", "7.9e-9\n",
              "*SOLID SECTION, ELSET=Eall, MATERIAL=STEEL\n", "*STEP\n", "*STATIC\n", "*BOUNDARY\n"]
    lines += [f"FIX{k}, 1, 3\n" for k in range(len(fixed))]
    if faces_of_solid_nodes:
        lines.append("*CLOAD\n")
        for k, f in faces_of_solid_nodes:
            lines += [f"LOAD{k}, {d + 1}, {f[d]:.12e}\n" for d in range(3)]  # a 20-character field
    if gravity:
        lines.append("*DLOAD\n")
        lines += [f"BODY{k}, GRAV, 9810., 0., 0., -1.\n" for k in gravity]
    lines += ["*NODE PRINT, NSET=Nall\n", "U\n", "*END STEP\n"]
    with open(os.path.join(workdir, "job.inp"), "w") as f:
        f.writelines(lines)
    t0 = time.perf_counter()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    try:
        run = subprocess.run([ccx, "job"], cwd=workdir, capture_output=True, text=True,
                             timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        raise InternalError(f"CalculiX did not finish within {timeout} s (see {workdir})") from None
    seconds = time.perf_counter() - t0
    log = run.stdout + run.stderr
    with open(os.path.join(workdir, "ccx.log"), "w") as f:
        f.write(log)
    refused = [ln.strip() for ln in log.splitlines()
               if "*ERROR" in ln or "nonpositive jacobian" in ln.lower()]
    if run.returncode != 0 or refused:
        raise InternalError("CalculiX refused the mesh: "
                            + ("; ".join(refused[:5]) or f"exit {run.returncode}")
                            + f" (see {workdir}/ccx.log)")
    u = _read_displacements(os.path.join(workdir, "job.dat"))
    if len(u) != len(mesh.points):
        raise InternalError(f"CalculiX printed {len(u)} displacements for {len(mesh.points)} "
                            f"nodes (see {workdir}/job.dat)")
    disp = np.array([u[i + 1] for i in range(len(mesh.points))])
    if not np.isfinite(disp).all():
        raise InternalError(f"CalculiX gave non-finite displacements (see {workdir}/job.dat)")
    fixed_nodes = np.concatenate([_face_nodes(result, f) for f in fixed])
    if np.abs(disp[fixed_nodes]).max() != 0.0:
        raise InternalError("a fixed node moved in the CalculiX result")
    lengths = np.linalg.norm(disp, axis=1)
    return {"groups": len(fixed), "fixed_faces": [f + 1 for f in fixed],
            "loaded_faces": [f + 1 for f in loaded], "gravity_groups": len(gravity),
            "nodes": int(len(mesh.points)), "elements": int(len(mesh.tets)), "order": order,
            "max_displacement": float(lengths.max()), "seconds": seconds,
            "finite": bool(math.isfinite(float(lengths.max())))}
