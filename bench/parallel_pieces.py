#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Benchmark (not a test): a solid meshed in pieces at the same time, on the threads of one
process and on the workers of a local Dask cluster, beside the core in one piece on one thread,
`tetgen -pY` and Gmsh's parallel HXT mesher on the same surfaces.

    bench/parallel_pieces.py [--families sphere,torus,cad] [--sizes 1e5,1e6] [--inputs FILE.off ...]
                             [--workers 2] [--cluster-workers 2,4]
                             [--meshers ours,threads,dask,tetgen,gmsh] [--mesher-binary PATH]
                             [--timeout S] [--gmsh-max-tets N] [--keep DIR] [--check]
                             [--markdown FILE] [--json FILE] [--note TEXT]

The surfaces are the scaling benchmark's (bench/scaling.py: a cube-sphere, a torus, the OCCT
bottle tessellated by FreeCAD; any size, e.g. ``--sizes 6.5e6 --families sphere`` for a mesh of
about 10^7 tets), or the OFF files of --inputs. Each run is a process of its own, one at a time,
timed by ``FemBspTet.peers.process.run_measured`` (wall seconds, peak RSS from GNU time):

* ``ours 1``: ``bsptet_mesh FILE.off --write STEM``: the core in memory, one piece, one thread;
* ``ours W threads``: ``bsptet_mesh FILE.off --workers W --write STEM``: the solid cut into about
  W pieces meshed on W threads (each piece's mesh checked exactly, as the whole mesh is in
  ``ours 1``: every run of ours checks its mesh, so the runs compare);
* ``ours Dask N``: this script with ``--dask-child``: a ``distributed.LocalCluster`` of N
  single-threaded worker processes on loopback, then
  ``FemBspTet.fem.pieces.tetrahedralize_in_pieces(surface, scheduler=ADDRESS, workers=N)``. Its
  seconds are reading the OFF and meshing (surface check, cut, pieces on the workers, each checked
  exactly there, merge); the cluster's start-up is reported apart, writing the mesh (done only for
  --check) is not timed. Its peak memory is each worker's (VmHWM) and the client's (which also
  runs the scheduler and the cut);
* ``tetgen -pY``: ``tetgen -pYQ FILE.off``;
* ``gmsh hxt 2 threads``: ``gmsh GEO -3 -algo hxt -nt 2`` on the same discrete surface, sized by
  the comparison's default rule (``CharacteristicLengthMax`` = the mean input edge length;
  FemBspTet.peers.gmsh). HXT refines the interior: its tet counts are not the core's, and they
  grow as the input's to the power 1.5 (about 3e6 at 10^5 sphere triangles, 10^9 at 6.5e6), so
  it is not run where it would make more than --gmsh-max-tets (default 6e7, about 12 GB).

A run over --timeout is recorded as ``timeout``. ``--check`` reads every mesh back and checks it
exactly against the input surface (``FemBspTet.kernel.core.check_mesh``; valid and volume equal),
outside the timed runs. Prints a table per input: seconds, peak MB, tets, pieces, the speed-up
over ``ours 1``, the parallel efficiency (speed-up / workers), the time ratios to ``tetgen -pY``
and to Gmsh's HXT, validity; --markdown (default docs/benchmarks/parallel-pieces.md) writes them
as a report (replaced by each run), --json the raw rows.
"""

import argparse
import json
import os
import shlex
import shutil
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "bench"))

import out_of_core  # noqa: E402 (bench/: the OFF runs, TetGen, the exact check of .node/.ele)
import scaling  # noqa: E402 (bench/: the surfaces, the tables)

MESHERS = ("ours", "threads", "dask", "tetgen", "gmsh")
GMSH_THREADS = 2
#: Gmsh's HXT fills the solid at the mean input edge length h: about this many tets per h^3 of
#: volume (measured: 4.1 on the 10^5 sphere, 4.4 on the torus), and about 200 bytes per tet.
HXT_TETS_PER_VOLUME = 4.2
_RESULT = "DASK_RESULT "


# ------------------------------------------------------------------------------------------
# the runs
# ------------------------------------------------------------------------------------------

def _outcome(run, timeout):
    """The common fields of a measured run: seconds, peak_mb, status, message."""
    row = {"seconds": run.seconds, "peak_mb": run.peak_rss_mb, "status": "ok", "message": ""}
    if run.timed_out:
        row.update(status="timeout", message=f"timeout after {timeout:g} s", seconds=timeout)
    elif run.returncode != 0:
        row.update(status="failed", message=(run.tail(1) or f"exit {run.returncode}")[:300])
    return row


def run_ours(binary, off, stem, timeout, workers=1):
    """``bsptet_mesh`` with its exact check of the mesh (or of each piece's)."""
    from FemBspTet.peers.process import run_measured

    command = [binary, off] + (["--workers", str(workers)] if workers > 1 else []) + ["--write", stem]
    run = run_measured(command, timeout=timeout, cwd=os.path.dirname(stem))
    row = _outcome(run, timeout)
    m = out_of_core._LINE.search(run.output)
    if row["status"] == "ok" and m is None:
        row.update(status="failed", message=run.tail(1)[:300])
    elif row["status"] == "ok":
        row.update(tets=int(m.group(2)), nodes=int(m.group(3)), valid=m.group(1).startswith("VALID"))
        p = out_of_core._PIECES.search(run.output)
        row["pieces"] = int(p.group(1)) if p else 1
    return row


def run_dask(off, stem, timeout, workers, write):
    """This script's --dask-child in a measured process of its own."""
    from FemBspTet.peers.process import run_measured, worker_env

    command = [sys.executable, os.path.abspath(__file__), "--dask-child", off, stem, str(workers)]
    run = run_measured(command + (["--write"] if write else []), timeout=timeout,
                       cwd=os.path.dirname(stem), env=worker_env())
    row = _outcome(run, timeout)
    row["process_seconds"], row["process_peak_mb"] = row["seconds"], row["peak_mb"]
    result = [ln for ln in run.output.splitlines() if ln.startswith(_RESULT)]
    if row["status"] == "ok" and not result:
        row.update(status="failed", message=run.tail(1)[:300])
    elif row["status"] == "ok":
        row.update(json.loads(result[-1][len(_RESULT):]))
        row["peak_mb"] = max(row["worker_peak_mb"])
    return row


def _vm_hwm_mb():
    """This process's peak resident memory (VmHWM, MB); runs on the Dask workers too."""
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    return None


def dask_child(off, stem, workers, write):
    """The --dask-child process: starts the cluster, meshes, prints one JSON line."""
    from distributed import Client, LocalCluster

    from FemBspTet.fem.pieces import tetrahedralize_in_pieces
    from FemBspTet.io.surface_io import read_surface
    from FemBspTet.io.volume_io import write_tet_mesh

    t0 = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        client.wait_for_workers(workers)
        t1 = time.perf_counter()
        mesh, stats = tetrahedralize_in_pieces(read_surface(off), scheduler=cluster.scheduler_address,
                                               workers=workers)
        t2 = time.perf_counter()
        peaks = client.run(_vm_hwm_mb)
        client_peak = _vm_hwm_mb()
    if write:
        write_tet_mesh(stem + ".node", mesh)
    print(_RESULT + json.dumps({
        "seconds": t2 - t1, "startup_seconds": t1 - t0, "tets": int(len(mesh.tets)),
        "nodes": int(len(mesh.points)), "pieces": int(stats["pieces"]["pieces"]),
        "valid": bool(stats["valid"]), "worker_peak_mb": sorted(peaks.values()),
        "client_peak_mb": client_peak}), flush=True)
    return 0


def run_tetgen(off, workdir, timeout):
    row, stem = out_of_core.run_tetgen(off, workdir, timeout)
    if row["status"] == "timeout":
        row["seconds"] = timeout
    if row["status"] == "ok":
        with open(stem + ".ele", encoding="ascii") as f:
            row["tets"] = int(f.readline().split()[0])
    return row, stem


def run_gmsh_hxt(surface, workdir, timeout, check, max_tets=None):
    """Gmsh's HXT on ``GMSH_THREADS`` threads, the .msh/.geo written as FemBspTet.peers.gmsh does;
    not run when it would make more than about ``max_tets`` tets (:data:`HXT_TETS_PER_VOLUME`)."""
    from FemBspTet.kernel import core
    from FemBspTet.kernel.errors import InternalError
    from FemBspTet.peers import gmsh

    size = gmsh.mean_edge_length(surface)
    expected = HXT_TETS_PER_VOLUME * scaling.signed_volume(surface.points, surface.triangles) / size ** 3
    if max_tets and expected > max_tets:
        return {"gmsh_size": size, "status": "not run", "message": f"would make about {expected:.2g} "
                f"tets at size {size:.3g} (over --gmsh-max-tets {max_tets:.2g})"}
    gmsh._write_surface_msh(os.path.join(workdir, "in.msh"), surface)
    geo, out = os.path.join(workdir, "surface.geo"), os.path.join(workdir, "out.msh")
    gmsh._write_geo(geo, "in.msh", size, remesh_surface=False)
    row = {"gmsh_size": size}
    try:
        run, mesh = gmsh._run_and_read([gmsh.gmsh_path(), geo, "-3", "-algo", "hxt", "-nt",
                                        str(GMSH_THREADS), "-format", "msh22", "-o", out],
                                       out, timeout, workdir)
    except InternalError as e:
        timed_out = "timed out" in str(e)
        row.update(status="timeout" if timed_out else "failed", message=str(e)[:300],
                   seconds=timeout if timed_out else None, peak_mb=None)
        return row
    row.update(status="ok", message="", seconds=run.seconds, peak_mb=run.peak_rss_mb,
               tets=len(mesh.tets), nodes=len(mesh.points))
    if check:  # Gmsh's own coincident nodes, then those the 16-digit round trip made
        row["duplicate_points"] = int(len(mesh.points) - len(np.unique(mesh.points, axis=0)))
        row["restored_points"] = gmsh.restore_input_points(mesh, surface)
        report = core.check_mesh(surface, mesh, max_messages=3, compute_quality=False)
        row["valid"] = bool(report["valid"] and report["volume_equal"])
        if not row["valid"]:
            row["message"] = "; ".join(report["messages"][:2])[:300] or "volume differs"
    return row


def runs_for(args):
    """``[(label, kind, workers)]`` in the order they run."""
    meshers = [m for m in args.meshers.split(",") if m]
    out = [("ours 1", "ours", 1)] if "ours" in meshers else []
    if "threads" in meshers:
        out += [(f"ours {w} threads", "threads", w) for w in _ints(args.workers)]
    if "dask" in meshers:
        out += [(f"ours Dask {n}", "dask", n) for n in _ints(args.cluster_workers)]
    if "tetgen" in meshers:
        out.append(("tetgen -pY", "tetgen", 1))
    if "gmsh" in meshers:
        out.append((f"gmsh hxt {GMSH_THREADS} threads", "gmsh", GMSH_THREADS))
    return out


def run_one(args, kind, workers, surface, off, workdir):
    stem = os.path.join(workdir, "mesh")
    if kind in ("tetgen", "gmsh") and shutil.which(kind) is None:
        return {"status": "not run", "message": f"{kind} is not installed"}
    if kind in ("ours", "threads"):
        row = run_ours(args.mesher_binary, off, stem, args.timeout, workers)
    elif kind == "dask":
        row = run_dask(off, stem, args.timeout, workers, args.check)
    elif kind == "tetgen":
        row, stem = run_tetgen(off, workdir, args.timeout)
    else:
        return run_gmsh_hxt(surface, workdir, args.timeout, args.check, args.gmsh_max_tets)
    if args.check and row["status"] == "ok":
        valid, _tets = out_of_core.check(surface, stem)
        row["valid"] = valid and row.get("valid", True)
    return row


# ------------------------------------------------------------------------------------------
# the tables and the report
# ------------------------------------------------------------------------------------------

def _ints(text):
    return [int(x) for x in str(text).split(",") if x.strip()]


def _ratio(a, b, fmt="{:.2f}"):
    ok = a and b and a["status"] == "ok" and b["status"] == "ok" and b["seconds"]
    return fmt.format(a["seconds"] / b["seconds"]) if ok else "-"


def table(rows):
    heads = ["mesher", "seconds", "peak MB", "tets", "pieces", "speed-up", "efficiency",
             "time / tetgen -pY", "time / gmsh hxt", "valid", "notes"]
    first = {}
    for r in rows:
        first.setdefault(r["kind"], r)
    one, tg, gm = first.get("ours"), first.get("tetgen"), first.get("gmsh")
    body = []
    for r in rows:
        ok = r["status"] == "ok"
        peak = "-"
        if ok and r["kind"] == "dask":
            peak = ", ".join(f"{x:.0f}" for x in r["worker_peak_mb"]) + " per worker"
        elif ok:
            peak = f"{r['peak_mb']:.0f}"
        speed = _ratio(one, r)
        eff = f"{float(speed) / r['workers']:.2f}" if speed != "-" else "-"
        notes = " ".join(r.get("message", "").split())[:160]
        if ok and r["kind"] == "dask":
            notes = (f"cluster start {r['startup_seconds']:.1f} s, process {r['process_seconds']:.1f} s; "
                     f"client {r['client_peak_mb']:.0f} MB")
        elif ok and r["kind"] == "gmsh":
            notes = f"size {r['gmsh_size']:.3g}" + (f"; {notes}" if notes else "")
        body.append([r["mesher"], f"{r['seconds']:.2f}" if ok else r["status"], peak,
                     str(r.get("tets", "-")), str(r.get("pieces", "-")), speed, eff,
                     _ratio(r, tg), _ratio(r, gm),
                     "-" if r.get("valid") is None else str(r["valid"]), notes])
    return heads, body


def machine(args):
    import dask
    import distributed

    from FemBspTet.compare.benchmark import environment

    env = environment()
    env.append(("cores this process may use", str(len(os.sched_getaffinity(0)))))
    env.append(("Dask", f"dask {dask.__version__}, distributed {distributed.__version__}"))
    ours = scaling._ours_environment(argparse.Namespace(ours="binary", mesher_binary=args.mesher_binary))
    return env + [(k, v.replace(ROOT + os.sep, "")) for k, v in ours]


def report(command, args, inputs, rows, env, elapsed):
    lines = ["# A solid meshed in pieces in parallel: threads, a Dask cluster, TetGen, Gmsh's HXT",
             "", f"Made by `{command}` in {elapsed / 60:.1f} min.", "",
             "| machine and versions | |", "|---|---|"] + [f"| {k} | {v} |" for k, v in env]
    lines += ["", "How to read it:",
              "- Each row is a process of its own, run one at a time on the same OFF file: seconds "
              "is its wall time (start-up, reading and writing included), peak MB its peak resident "
              "memory (GNU time).",
              "- ours 1: `bsptet_mesh FILE.off --write STEM`, the core in one piece on one thread; "
              "ours W threads: `bsptet_mesh FILE.off --workers W --write STEM`, the solid cut into "
              "about W pieces meshed on W threads. Both check their mesh exactly (each piece's, in "
              "pieces) inside the timed run.",
              "- ours Dask N: a `distributed.LocalCluster` of N single-threaded worker processes on "
              "127.0.0.1 and `tetrahedralize_in_pieces(surface, scheduler=ADDRESS, workers=N)`. "
              "Seconds: reading the OFF and meshing (surface check, cut, pieces meshed and checked "
              "exactly on the workers, merge), without the cluster's start-up (in the notes, with "
              "the whole process's wall time) and without writing the mesh. Peak MB: each worker "
              "process's VmHWM; the client's (which also runs the scheduler and the cut) is in the "
              "notes.",
              "- tetgen -pY: `tetgen -pYQ`, one thread. gmsh hxt: `gmsh GEO -3 -algo hxt -nt "
              f"{GMSH_THREADS}` on the discrete surface, CharacteristicLengthMax = the mean input "
              "edge length (the comparison's default); HXT refines the interior, so its tets are "
              "more and its times are not the same job; it is not run where it would make more "
              f"than {args.gmsh_max_tets:.2g} tets (--gmsh-max-tets).",
              "- speed-up: seconds of ours 1 / seconds of the row; efficiency: speed-up / the row's "
              "workers (threads or processes); time / tetgen -pY and time / gmsh hxt: the row's "
              "seconds over theirs (below 1: faster).",
              "- valid: " + ("every mesh read back and checked exactly against the input surface "
                             "(conforming, positive, boundary = the input, volume equal) outside the "
                             "timed runs, and for ours also the check inside the run."
                             if args.check else
                             "the check inside our runs; peers' meshes are not checked (no --check)."),
              f"- A run over {args.timeout:g} s is `timeout`.", ""]
    lines += [f"- {n}" for n in args.note] + ([""] if args.note else [])
    for inp in inputs:
        heads, body = table([r for r in rows if r["input"] == inp["name"]])
        lines += [f"## {inp['name']}: {inp['triangles']} triangles, {inp['points']} points",
                  "", inp["note"], "", scaling.md_table(heads, body), ""]
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------
# main
# ------------------------------------------------------------------------------------------

def make_inputs(args, workdir):
    """``[(input dict, OFF path)]``: the --inputs, or the families at the sizes."""
    from FemBspTet.io.surface_io import write_surface

    if args.inputs:
        return [({"name": os.path.splitext(os.path.basename(p))[0], "note": f"OFF file {os.path.basename(p)}"},
                 os.path.abspath(p)) for p in args.inputs]
    out = []
    for size in scaling.parse_sizes(args.sizes):
        for fam in [f for f in args.families.split(",") if f]:
            if fam == "cad" and scaling.freecad_problem():
                args.note.append(f"cad skipped: FreeCAD does not load ({scaling.freecad_problem()})")
                print(args.note[-1])
                continue
            surface, note = scaling.make_surface(fam, size, log=print)
            off = os.path.join(workdir, f"{fam}_{size}.off")
            write_surface(off, surface)
            del surface
            out.append(({"name": f"{fam}_{size}", "note": note}, off))
    return out


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--dask-child":
        return dask_child(argv[1], argv[2], int(argv[3]), "--write" in argv[4:])
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--families", default="sphere,torus,cad", help="of sphere, torus, cad")
    ap.add_argument("--sizes", default="1e5,1e6", help="target triangle counts (any size)")
    ap.add_argument("--inputs", nargs="*", default=[], help="OFF files instead of the families")
    ap.add_argument("--workers", default="2", help="thread counts of 'ours W threads'")
    ap.add_argument("--cluster-workers", default="2,4", help="worker processes of 'ours Dask N'")
    ap.add_argument("--meshers", default=",".join(MESHERS), help="of " + ", ".join(MESHERS))
    ap.add_argument("--mesher-binary", default=os.path.join(ROOT, "build", "cpp_module", "bsptet_mesh"))
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per run (default 1800)")
    ap.add_argument("--gmsh-max-tets", type=float, default=6e7,
                    help="skip Gmsh where it would make more tets than this (about 200 bytes "
                         "each; default 6e7; 0: no limit)")
    ap.add_argument("--keep", default=None, metavar="DIR", help="keep the inputs and meshes here")
    ap.add_argument("--check", action="store_true", help="check every mesh exactly (untimed)")
    ap.add_argument("--markdown", default=os.path.join(ROOT, "docs", "benchmarks", "parallel-pieces.md"))
    ap.add_argument("--json", default=None, metavar="FILE", help="write the raw rows")
    ap.add_argument("--note", action="append", default=[], help="a line for the report")
    args = ap.parse_args(argv)
    for m in args.meshers.split(","):
        if m and m not in MESHERS:
            ap.error(f"unknown mesher {m}")
    if not os.access(args.mesher_binary, os.X_OK):
        ap.error(f"no executable {args.mesher_binary}")
    # The report's command without the options that name files of this machine's run.
    shown = [a for i, a in enumerate(argv) if a not in ("--json", "--keep")
             and (i == 0 or argv[i - 1] not in ("--json", "--keep"))]
    command = "bench/parallel_pieces.py " + shlex.join(shown)
    from FemBspTet.io.atomic_file import atomic_output
    from FemBspTet.io.surface_io import read_surface

    workdir = args.keep or tempfile.mkdtemp(prefix="fembsptet_parallel_")
    os.makedirs(workdir, exist_ok=True)
    started = time.time()
    inputs, rows = [], []
    try:
        for inp, off in make_inputs(args, workdir):
            surface = read_surface(off)
            inp.update(triangles=int(len(surface.triangles)), points=int(len(surface.points)))
            inputs.append(inp)
            print(f"{inp['name']}: {inp['triangles']} triangles ({inp['note']})", flush=True)
            for k, (label, kind, workers) in enumerate(runs_for(args)):
                d = os.path.join(workdir, f"{inp['name']}.{k}")
                os.makedirs(d, exist_ok=True)
                row = {"input": inp["name"], "triangles": inp["triangles"], "mesher": label,
                       "kind": kind, "workers": workers}
                row.update(run_one(args, kind, workers, surface, off, d))
                rows.append(row)
                print(f"  {label:18s} {row['status']:7s} {row.get('seconds') or 0:8.2f} s "
                      f"{row.get('peak_mb') or 0:7.0f} MB tets {row.get('tets', '-')} "
                      f"valid {row.get('valid')} {row.get('message', '')}", flush=True)
                if not args.keep:
                    shutil.rmtree(d, ignore_errors=True)
    finally:
        if not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)
    elapsed = time.time() - started
    for inp in inputs:
        heads, body = table([r for r in rows if r["input"] == inp["name"]])
        print(f"\n{inp['name']} ({inp['triangles']} triangles)\n" + scaling.text_table(heads, body))
    env = machine(args)
    if args.json:
        with atomic_output(args.json) as f:
            json.dump({"command": command, "timeout": args.timeout, "environment": env,
                       "elapsed_seconds": round(elapsed, 1), "inputs": inputs, "rows": rows}, f, indent=1)
    if args.markdown:
        with atomic_output(args.markdown) as f:
            f.write(report(command, args, inputs, rows, env, elapsed))
    return 0


if __name__ == "__main__":
    sys.exit(main())
