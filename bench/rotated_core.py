# SPDX-License-Identifier: LGPL-2.1-or-later
"""Benchmark (not a test): the core on CAD tessellations as given and under random rotations.

    bench/rotated_core.py [MODELS ...] [--corpus DIR] [--program PATH] [--timeout S] [--markdown FILE]

A rotation makes the planar faces of a CAD tessellation generic: their vertices are coplanar only
up to rounding. For each model (an OFF surface, by path or by name in --corpus) the core's own
program (``bsptet_mesh --no-check``) and ``tetgen -pY`` mesh the surface as given and under 3
fixed random rotations (numpy's default_rng seeds 1, 2, 3; the rotation of
tests/test_mesher_properties.py). Printed and written to the report: the core's seconds (its own
figure, reading and checking left out), its seed's missing input edges and the conflicts (seed
tets crossed by an input triangle), TetGen's wall-clock seconds, and the ratio rotated /
unrotated of each. The requirement the report checks: the core's time on a rotated surface within
1.5 times its time on the surface as given.

Default models: thingi10k_1514499 and no_print_feeder_body (of the public corpus; --corpus or
FEMBSPTET_CORPUS names its meshes folder, default tests/data/corpus), hinge, pinion and anchor.
The report goes to docs/benchmarks/rotated-core.md unless --markdown says otherwise; it is
overwritten on every run.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from FemBspTet.io.surface_io import read_surface  # noqa: E402

DEFAULT_MODELS = ("thingi10k_1514499", "no_print_feeder_body", "hinge", "pinion", "anchor")
ROTATION_SEEDS = (1, 2, 3)
LIMIT = 1.5


def random_rotation(seed):
    """The rotation tests/test_mesher_properties.py uses: QR of a normal matrix, det +1."""
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def write_off(path, points, triangles):
    """Plain OFF with shortest round-trip doubles and no comment line (TetGen's reader stops at one)."""
    with open(path, "w") as f:
        f.write(f"OFF\n{len(points)} {len(triangles)} 0\n")
        f.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
        f.writelines(f"3 {a} {b} {c}\n" for a, b, c in triangles.tolist())


def run_core(program, path, timeout):
    """(core seconds, missing seed edges, seed conflicts, status) of bsptet_mesh --no-check."""
    try:
        p = subprocess.run([program, path, "--no-check"], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, None, None, f"timeout {timeout:g} s"
    out = p.stdout
    if p.returncode != 0 or "UNCHECKED" not in out:
        line = (out.strip().splitlines() or p.stderr.strip().splitlines() or ["?"])[0]
        return None, None, None, "failed: " + os.path.basename(line)
    seconds = float(re.search(r" seconds ([0-9.eE+-]+)", out).group(1))
    missing = re.search(r"missing edges (\d+) recovered (\d+)", out)
    conflicts = re.search(r" conflicts (\d+)", out)
    left = int(missing.group(1)) - int(missing.group(2)) if missing else None
    return seconds, left, int(conflicts.group(1)) if conflicts else None, "ok"


def run_tetgen(path, workdir, timeout):
    """Wall-clock seconds of tetgen -pY on a copy of the surface in workdir (its outputs land there)."""
    local = os.path.join(workdir, "tg.off")
    shutil.copyfile(path, local)
    t0 = time.perf_counter()
    try:
        p = subprocess.run(["tetgen", "-pYQ", local], capture_output=True, text=True, timeout=timeout)
    except (subprocess.TimeoutExpired, FileNotFoundError) as e:
        return None, type(e).__name__
    seconds = time.perf_counter() - t0
    return (seconds, "ok") if p.returncode == 0 else (None, f"rc {p.returncode}")


def ratio(x, base):
    return None if x is None or not base else x / base


def fmt(x, digits=2):
    return "-" if x is None else f"{x:.{digits}f}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="*")
    ap.add_argument("--corpus", default=os.environ.get("FEMBSPTET_CORPUS", os.path.join(ROOT, "tests", "data", "corpus")),
                    help="folder of the models named without a path")
    ap.add_argument("--program", default=os.path.join(ROOT, "build", "cpp_module", "bsptet_mesh"))
    ap.add_argument("--timeout", type=float, default=600.0)
    ap.add_argument("--markdown", default=os.path.join(ROOT, "docs", "benchmarks", "rotated-core.md"))
    args = ap.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for model in args.models or DEFAULT_MODELS:
            path = model if os.path.exists(model) else os.path.join(args.corpus, model + ".off")
            name = os.path.splitext(os.path.basename(path))[0]
            if not os.path.exists(path):
                print(f"{name}: not found, skipped")
                rows.append({"model": name, "rotation": "-", "status": "not found"})
                continue
            surface = read_surface(path)
            base_core = base_tg = None
            for seed in (None,) + ROTATION_SEEDS:
                if seed is None:
                    run_path = path
                else:
                    run_path = os.path.join(tmp, f"{name}_r{seed}.off")
                    write_off(run_path, surface.points @ random_rotation(seed).T, surface.triangles)
                core_s, left, conflicts, status = run_core(args.program, run_path, args.timeout)
                tg_s, tg_status = run_tetgen(run_path, tmp, args.timeout)
                if seed is None:
                    base_core, base_tg = core_s, tg_s
                row = {"model": name, "rotation": "none" if seed is None else f"seed {seed}",
                       "triangles": len(surface.triangles), "core_s": core_s, "missing": left,
                       "conflicts": conflicts, "tetgen_s": tg_s, "core_ratio": ratio(core_s, base_core),
                       "tetgen_ratio": ratio(tg_s, base_tg), "status": status if tg_status == "ok" else
                       f"{status}; tetgen {tg_status}"}
                rows.append(row)
                print(f"{name:24s} {row['rotation']:8s} core {fmt(core_s)} s (x{fmt(row['core_ratio'])}) "
                      f"missing edges {left} conflicts {conflicts}  tetgen {fmt(tg_s)} s "
                      f"(x{fmt(row['tetgen_ratio'])})  {row['status']}", flush=True)
    # The command as run, without folders (no machine paths in the report).
    command = ["bench/rotated_core.py"] + [os.path.splitext(os.path.basename(m))[0] for m in args.models]
    if args.timeout != 600.0:
        command.append(f"--timeout {args.timeout:g}")
    text = report(rows, " ".join(command))
    if args.markdown:
        from FemBspTet.io.atomic_file import atomic_output

        with atomic_output(args.markdown) as f:
            f.write(text)
    worst = max((r["core_ratio"] for r in rows if r.get("core_ratio") is not None), default=None)
    print(f"largest core ratio rotated / unrotated: {fmt(worst)} (limit {LIMIT})")
    return 0


def report(rows, command):
    lines = ["# The core on rotated CAD tessellations", "",
             f"`{command.strip()}`: each surface as given and under 3 fixed random rotations. Core: the "
             "seconds `bsptet_mesh --no-check` reports for the core (reading and the output check left "
             "out); missing edges: input edges the seed's flips did not recover; conflicts: (seed tet, "
             "input triangle) pairs where the triangle crosses the tet. TetGen: wall-clock seconds of "
             "`tetgen -pYQ`. Ratios: rotated / as given. "
             f"The requirement: the core's ratio at most {LIMIT}.", "",
             "| model | triangles | rotation | core s | core ratio | missing edges | conflicts | tetgen s | tetgen ratio | status |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['model']} | {r.get('triangles', '-')} | {r['rotation']} | {fmt(r.get('core_s'))} | "
                     f"{fmt(r.get('core_ratio'))} | {r.get('missing', '-')} | {r.get('conflicts', '-')} | "
                     f"{fmt(r.get('tetgen_s'))} | {fmt(r.get('tetgen_ratio'))} | {r['status']} |")
    ratios = [r["core_ratio"] for r in rows if r.get("core_ratio") is not None and r["rotation"] != "none"]
    if ratios:
        over = sum(1 for x in ratios if x > LIMIT)
        lines += ["", f"Largest core ratio: {max(ratios):.2f}; rotated runs over {LIMIT}: {over} of {len(ratios)}."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
