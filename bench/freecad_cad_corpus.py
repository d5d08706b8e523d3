#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Every CAD file of a folder through the FreeCAD mesher pipeline (the FEM path), each in a worker
process with a time limit: either a mesh (nodes, tets, seconds) or the message the user would see.
Usage:

    bench/freecad_cad_corpus.py [FOLDER_OR_FILES ...] [--order 1|2] [--size-of-diagonal F]
                                [--timeout S] [--markdown F]

Default folder: tests/data/cad. Prints one row per file; --markdown (default
docs/benchmarks/freecad-cad-corpus.md) writes them as a report.
"""

import argparse
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from FemBspTet.io.cad_tessellation import CAD_FORMATS  # noqa: E402
from FemBspTet.compare.benchmark import model_paths  # noqa: E402
from FemBspTet.kernel.errors import BspTetError  # noqa: E402
from FemBspTet.kernel.freecad_env import import_freecad  # noqa: E402
from FemBspTet.fem.mesh_pipeline import MeshParameters  # noqa: E402
from FemBspTet.freecad.mesh_worker import MeshJob  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("inputs", nargs="*", default=[os.path.join(ROOT, "tests", "data", "cad")])
    ap.add_argument("--order", type=int, choices=(1, 2), default=1)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--markdown", default=os.path.join(ROOT, "docs", "benchmarks", "freecad-cad-corpus.md"))
    ap.add_argument("--size-of-diagonal", type=float, default=0.0, metavar="F",
                    help="CharacteristicLengthMax = F * the shape's bounding-box diagonal "
                         "(default 0: automatic, the mesher object's default)")
    args = ap.parse_args()
    import_freecad()
    import Part

    rows = [("file", "solids", "faces", "result", "nodes", "tets", "seconds", "min dihedral",
             "1% dihedral")]
    for path in model_paths(args.inputs, CAD_FORMATS):
        name = os.path.basename(path)
        t0 = time.perf_counter()
        try:
            shape = Part.read(path)
        except Exception as e:
            rows.append((name, "-", "-", "unreadable: %s" % e, "", "", ""))
            print(" | ".join(str(c) for c in rows[-1]), flush=True)
            continue
        size = args.size_of_diagonal * shape.BoundBox.DiagonalLength
        job = MeshJob(shape, MeshParameters(max_size=size, order=args.order, compare_peers=False),
                      source=name, python="/usr/bin/python3")
        job.start()
        if not job.wait(args.timeout):
            job.cancel()
            rows.append((name, len(shape.Solids), len(shape.Faces),
                         "stopped after %g s" % args.timeout, "", "", ""))
            print(" | ".join(str(c) for c in rows[-1]), flush=True)
            continue
        try:
            r = job.result()
            p1 = r.stats.get("p1_dihedral_deg")
            rows.append((name, len(shape.Solids), len(shape.Faces), "ok", len(r.mesh.points),
                         len(r.mesh.tets), "%.1f" % (time.perf_counter() - t0),
                         "%.2f" % r.stats["min_dihedral_deg"], "" if p1 is None else "%.1f" % p1))
        except BspTetError as e:
            msg = str(e).replace("\n", " ")
            rows.append((name, len(shape.Solids), len(shape.Faces),
                         "%s: %s" % (type(e).__name__, msg[:240]), "", "",
                         "%.1f" % (time.perf_counter() - t0)))
        print(" | ".join(str(c) for c in rows[-1]), flush=True)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write("| " + " | ".join(rows[0]) + " |\n|" + "---|" * len(rows[0]) + "\n")
            for r in rows[1:]:
                f.write("| " + " | ".join(str(c) for c in r) + " |\n")
    ok = sum(1 for r in rows[1:] if r[3] == "ok")
    print("%d of %d files meshed (order %d)" % (ok, len(rows) - 1, args.order))


if __name__ == "__main__":
    main()
