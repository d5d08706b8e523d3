#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Benchmark (not a test): our core beside `tetgen -pY` on the same surfaces.

    bench/core_vs_tetgen.py [MODELS_OR_FOLDERS ...] [--timeout S] [--repeats N] [--markdown FILE]

The comparison of ``fembsptet benchmark`` (FemBspTet/compare/benchmark.py) restricted to our
mesher (twice: the Python worker users run, and the C++ core's own program ``bsptet_mesh
--no-check``, timed like TetGen's program without the worker's start-up and check; both meshes
are checked by the benchmark) and ``tetgen -pY`` (default models: tests/data/paper and tests/data/corpus): per model
nodes, tets, Steiner points, dihedral angles, seconds and peak memory of each mesher's own
process, whether our exact checker accepts each mesh, then the ratios against TetGen and their
medians. ``fembsptet benchmark`` adds Gmsh. ``--repeats N`` (default 5): a run shorter than a
second is made N times in all and timed by the median (single runs of a few milliseconds vary by
tens of percent on a shared machine, and most of the models here are that small). The report goes
to docs/benchmarks/core-vs-tetgen.md unless --markdown says otherwise.
"""

import argparse
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from FemBspTet.compare.benchmark import model_paths, report_markdown, run_benchmark  # noqa: E402
from FemBspTet.compare.comparison import OURS, OURS_NATIVE, TETGEN_PY  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="*")
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--repeats", type=int, default=5,
                    help="runs shorter than 1 s are made this many times; their median is used")
    ap.add_argument("--markdown", default=os.path.join(ROOT, "docs", "benchmarks", "core-vs-tetgen.md"),
                    help="also write the report as markdown here")
    args = ap.parse_args(argv)
    paths = model_paths(args.models or [os.path.join(ROOT, "tests/data/paper"),
                                        os.path.join(ROOT, "tests/data/corpus")])
    entries = run_benchmark(paths, timeout=args.timeout, meshers=(OURS, OURS_NATIVE, TETGEN_PY),
                            log=print, repeats=args.repeats)
    text = report_markdown(entries, "bench/core_vs_tetgen.py " + " ".join(sys.argv[1:]),
                           repeats=args.repeats)
    print(text[text.index("## Ratios"):])
    if args.markdown:
        from FemBspTet.io.atomic_file import atomic_output

        with atomic_output(args.markdown) as f:
            f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
