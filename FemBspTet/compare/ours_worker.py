# SPDX-License-Identifier: LGPL-2.1-or-later
"""Our mesher in a process of its own, so that the comparison measures it as it measures TetGen and
Gmsh (wall time and peak memory of one process, :func:`.process.run_measured`).

    /usr/bin/python3 -m FemBspTet.compare.ours_worker OPTIONS_JSON OUT_DIR SURFACE.off [...]

Meshes each surface (one per solid) with ``core.tetrahedralize(surface, options)`` and writes
``OUT_DIR/<surface stem>.vtu`` (round-trip precision) and ``OUT_DIR/ours_stats.json`` (the
core's stats per solid). Errors are reported as ``fembsptet`` reports them (one line on stderr,
exit 2 for bad input, 1 otherwise: :func:`FemBspTet.kernel.errors.report_errors`).
"""

import json
import os
import sys

from ..io.atomic_file import atomic_output
from ..io.surface_io import read_surface
from ..io.volume_io import write_tet_mesh
from ..kernel import core
from ..kernel.errors import report_errors


def ours_mesh_path(out_dir, surface_path):
    """Where the worker writes the mesh of ``surface_path``."""
    stem = os.path.splitext(os.path.basename(surface_path))[0]
    return os.path.join(out_dir, stem + ".vtu")


def _run(args):

    options_json, out_dir, paths = args
    options = json.loads(options_json)
    stats = []
    for path in paths:
        mesh, st = core.tetrahedralize(read_surface(path), options=options)
        write_tet_mesh(ours_mesh_path(out_dir, path), mesh)
        stats.append({k: v for k, v in st.items() if k != "dihedral_histogram"})
    with atomic_output(os.path.join(out_dir, "ours_stats.json")) as f:
        json.dump(stats, f, indent=1, default=str)
    return 0


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if len(argv) < 3:
        print("usage: python3 -m FemBspTet.compare.ours_worker OPTIONS_JSON OUT_DIR SURFACE...",
              file=sys.stderr)
        return 2
    return report_errors(_run, (argv[0], argv[1], argv[2:]))


if __name__ == "__main__":
    sys.exit(main())
