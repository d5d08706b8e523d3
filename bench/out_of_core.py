#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Benchmark (not a test): the out-of-core mode beside the in-memory core and
`tetgen -pY` on the same surfaces: wall time and peak memory of each run, in the same process tree.

    bench/out_of_core.py [--families sphere,torus,cad] [--sizes 1e5,1e6] [--budgets 400M,200M]
                         [--inputs FILE.off ...] [--meshers ours,pieces,tetgen-pY]
                         [--mesher-binary PATH] [--timeout S] [--keep DIR] [--check]
                         [--markdown FILE] [--note TEXT]

The surfaces are the scaling benchmark's (bench/scaling.py: a cube-sphere, a torus, the OCCT
bottle tessellated by FreeCAD), or the OFF files of --inputs. Each run is a process of its own,
timed by ``FemBspTet.peers.process.run_measured`` (wall time, peak RSS from GNU time):

* ``ours``: ``bsptet_mesh FILE.off --no-check --write STEM`` (the core in memory);
* ``pieces``: ``bsptet_mesh FILE.off --max-memory B --no-check --write STEM`` for each budget B:
  the solid cut into pieces whose estimated peak fits B, meshed one after the other and streamed
  to disk (out_of_core.h);
* ``tetgen-pY``: ``tetgen -pYQ``.

``--check`` reads every mesh back and checks it exactly against the input surface (untimed).
Prints a table: seconds, peak MB, the peak's ratio to the budget and to the in-memory run, tets,
pieces, and validity; --markdown (default docs/benchmarks/out-of-core.md) writes it as a report.
"""

import argparse
import os
import re
import shlex
import shutil
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "bench"))

_LINE = re.compile(r":\s*(VALID[^ ]*|INVALID|UNCHECKED)(?: \(each piece checked exactly\))? tets (\d+) points (\d+)")
_PIECES = re.compile(r"pieces (\d+) \(largest (\d+) triangles, at most (\d+)\) cuts (\d+) \(refused (\d+)\)")


def parse_size(text):
    from FemBspTet.kernel.memory_budget import parse_size as parse

    return parse(text, option="--budgets")


def run_ours(binary, off, stem, timeout, budget=None):
    from FemBspTet.peers.process import run_measured

    command = [binary, off, "--no-check", "--write", stem]
    if budget is not None:
        command += ["--max-memory", str(budget)]
    run = run_measured(command, timeout=timeout, cwd=os.path.dirname(stem))
    row = {"seconds": run.seconds, "peak_mb": run.peak_rss_mb, "status": "ok", "message": ""}
    m = _LINE.search(run.output)
    if run.timed_out:
        row.update(status="timeout", message=f"timeout after {timeout:g} s")
    elif run.returncode != 0 or m is None:
        row.update(status="failed", message=(run.tail(1) or f"exit {run.returncode}")[:300])
    else:
        row["tets"], row["nodes"] = int(m.group(2)), int(m.group(3))
        p = _PIECES.search(run.output)
        if p:
            row["pieces"], row["largest_piece"], row["piece_limit"] = int(p.group(1)), int(p.group(2)), int(p.group(3))
            row["cuts_refused"] = int(p.group(5))
        row["uncut"] = run.output.count("could not be cut")
    return row


def run_tetgen(off, workdir, timeout):
    from FemBspTet.peers.process import run_measured

    local = os.path.join(workdir, "tetgen_input.off")
    with open(off, encoding="ascii") as src, open(local, "w", encoding="ascii") as dst:
        for line in src:  # TetGen 1.5 aborts on OFF comment lines
            if not line.lstrip().startswith("#"):
                dst.write(line)
    run = run_measured(["tetgen", "-pYQ", local], timeout=timeout, cwd=workdir)
    row = {"seconds": run.seconds, "peak_mb": run.peak_rss_mb, "status": "ok", "message": ""}
    if run.timed_out:
        row.update(status="timeout", message=f"timeout after {timeout:g} s")
    elif run.returncode != 0:
        row.update(status="failed", message=(run.tail(1) or f"exit {run.returncode}")[:300])
    return row, os.path.join(workdir, "tetgen_input.1")


def check(surface, stem):
    from FemBspTet.kernel import core
    from FemBspTet.io.volume_io import read_tetgen

    mesh = read_tetgen(stem)
    report = core.check_mesh(surface, mesh, max_messages=3, compute_quality=False)
    return bool(report["valid"] and report["volume_equal"]), len(mesh.tets)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--families", default="sphere,torus,cad")
    ap.add_argument("--sizes", default="1e5")
    ap.add_argument("--inputs", nargs="*", default=[], help="OFF files instead of the families")
    ap.add_argument("--budgets", default="400M", help="comma-separated memory budgets for 'pieces'")
    ap.add_argument("--meshers", default="ours,pieces,tetgen-pY")
    ap.add_argument("--mesher-binary", default=os.path.join(ROOT, "build", "cpp_module", "bsptet_mesh"))
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--keep", default=None, metavar="DIR")
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--markdown", default=os.path.join(ROOT, "docs", "benchmarks", "out-of-core.md"))
    ap.add_argument("--note", action="append", default=[])
    args = ap.parse_args(argv)
    command = "bench/out_of_core.py " + shlex.join(sys.argv[1:] if argv is None else argv)
    meshers = [m for m in args.meshers.split(",") if m]
    budgets = [(b, parse_size(b)) for b in args.budgets.split(",") if b]
    from FemBspTet.io.surface_io import read_surface, write_surface

    workdir = args.keep or tempfile.mkdtemp(prefix="fembsptet_ooc_")
    os.makedirs(workdir, exist_ok=True)
    inputs = []
    if args.inputs:
        inputs = [(os.path.splitext(os.path.basename(p))[0], os.path.abspath(p)) for p in args.inputs]
    else:
        import scaling

        for size in [float(s) for s in args.sizes.split(",") if s]:
            for fam in [f for f in args.families.split(",") if f]:
                if fam == "cad" and scaling.freecad_problem():
                    print(f"cad skipped: {scaling.freecad_problem()}")
                    continue
                surf, _note = scaling.make_surface(fam, size, log=print)
                off = os.path.join(workdir, f"{fam}_{int(size)}.off")
                write_surface(off, surf)
                inputs.append((f"{fam}_{int(size)}", off))
    rows = []
    started = time.time()
    try:
        for name, off in inputs:
            surface = read_surface(off)
            runs = []
            if "ours" in meshers:
                runs.append(("ours (in memory)", None))
            if "pieces" in meshers:
                runs += [(f"pieces, budget {label}", size) for label, size in budgets]
            for label, budget in runs:
                d = os.path.join(workdir, f"{name}.{len(rows)}")
                os.makedirs(d, exist_ok=True)
                stem = os.path.join(d, "mesh")
                row = {"input": name, "triangles": len(surface.triangles), "mesher": label, "budget": budget}
                row.update(run_ours(args.mesher_binary, off, stem, args.timeout, budget))
                if args.check and row["status"] == "ok":
                    row["valid"], _ = check(surface, stem)
                rows.append(row)
                print(_line(row), flush=True)
                if not args.keep:
                    shutil.rmtree(d, ignore_errors=True)
            if "tetgen-pY" in meshers:
                d = os.path.join(workdir, f"{name}.tetgen")
                os.makedirs(d, exist_ok=True)
                row = {"input": name, "triangles": len(surface.triangles), "mesher": "tetgen -pY", "budget": None}
                result, stem = run_tetgen(off, d, args.timeout)
                row.update(result)
                if row["status"] == "ok":
                    valid, tets = check(surface, stem) if args.check else (None, None)
                    row["valid"] = valid
                    if tets is None:
                        with open(stem + ".ele", encoding="ascii") as f:
                            tets = int(f.readline().split()[0])
                    row["tets"] = tets
                rows.append(row)
                print(_line(row), flush=True)
                if not args.keep:
                    shutil.rmtree(d, ignore_errors=True)
    finally:
        if not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)
    heads, body = _table(rows)
    print(_text(heads, body))
    if args.markdown:
        from FemBspTet.io.atomic_file import atomic_output

        with atomic_output(args.markdown) as f:
            f.write("# Out-of-core mode against the in-memory core and TetGen\n\n")
            f.write(f"Command: `{command}` ({time.time() - started:.0f} s in all).\n\n")
            f.write("Wall seconds and peak RSS of each process (GNU time), one run each; `--no-check` "
                    "runs, then every mesh read back and checked exactly against the input "
                    "(`valid`: conforming, positive, boundary = the input, volume equal).\n\n")
            for note in args.note:
                f.write(f"{note}\n\n")
            f.write("| " + " | ".join(heads) + " |\n|" + "---|" * len(heads) + "\n")
            for b in body:
                f.write("| " + " | ".join(b) + " |\n")
    return 0


def _line(row):
    return (f"{row['input']}: {row['mesher']}: {row['status']} {row.get('seconds') or 0:.1f} s "
            f"{row.get('peak_mb') or 0:.0f} MB tets {row.get('tets')} pieces {row.get('pieces', '-')} "
            f"valid {row.get('valid')} {row.get('message', '')}")


def _table(rows):
    heads = ["input", "triangles", "mesher", "seconds", "peak MB", "peak / budget", "peak / in memory",
             "time / in memory", "time / TetGen", "tets", "pieces", "valid"]
    body = []
    for r in rows:
        same = [x for x in rows if x["input"] == r["input"]]
        mem = next((x for x in same if x["mesher"].startswith("ours") and x["status"] == "ok"), None)
        tg = next((x for x in same if x["mesher"].startswith("tetgen") and x["status"] == "ok"), None)
        ok = r["status"] == "ok"
        body.append([r["input"], str(r["triangles"]), r["mesher"],
                     f"{r['seconds']:.1f}" if ok else r["status"],
                     f"{r['peak_mb']:.0f}" if ok else "-",
                     f"{r['peak_mb'] * 2**20 / r['budget']:.2f}" if ok and r.get("budget") else "-",
                     f"{r['peak_mb'] / mem['peak_mb']:.2f}" if ok and mem else "-",
                     f"{r['seconds'] / mem['seconds']:.2f}" if ok and mem else "-",
                     f"{r['seconds'] / tg['seconds']:.2f}" if ok and tg else "-",
                     str(r.get("tets", "-")),
                     (f"{r['pieces']}" + (f" ({r['uncut']} uncut)" if r.get("uncut") else "")) if r.get("pieces") else "-",
                     "-" if r.get("valid") is None else str(r["valid"])])
    return heads, body


def _text(heads, body):
    widths = [max(len(x) for x in col) for col in zip(heads, *body)]
    fmt = "  ".join(("{:<%d}" if i < 3 else "{:>%d}") % w for i, w in enumerate(widths))
    return "\n".join([fmt.format(*heads)] + [fmt.format(*b) for b in body])


if __name__ == "__main__":
    sys.exit(main())
