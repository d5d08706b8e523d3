#!/usr/bin/python3
"""Benchmark (not a test): our core beside `tetgen -pY` on the same surfaces.

    bench/core_vs_tetgen.py [MODELS_OR_FOLDERS ...] [--timeout S] [--markdown FILE]

For each surface (default: tests/data/paper and tests/data/corpus) it runs `fembsptet mesh` and
`tetgen -pY` as separate processes of this process tree, and prints per model: our result (valid
mesh or the error), seconds (the core's own clock, without Python's start-up; TetGen's is its
process's wall time, start-up included), peak memory of the whole process, Steiner points and tets, TetGen's, and the ratios
ours/TetGen, then the medians of the ratios over the models both meshed. Our meshes are checked
exactly by `fembsptet mesh` itself (it refuses to write an invalid one).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from FemBspTet.compare.tetgen_backend import run_tetgen, tetgen_available  # noqa: E402
from FemBspTet.errors import BspTetError  # noqa: E402
from FemBspTet.surface_io import read_surface  # noqa: E402


def run_ours(path, timeout):
    with tempfile.TemporaryDirectory() as tmp:
        stats_file = os.path.join(tmp, "stats.json")
        cmd = [os.path.join(ROOT, "bin", "fembsptet"), "mesh", path, "-o", os.path.join(tmp, "m.vtu"),
               "--stats-json", stats_file, "--quiet"]
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = t0 + timeout
        status, rusage = 0, None
        while True:
            pid, status, rusage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() > deadline:
                proc.kill()
                pid, status, rusage = os.wait4(proc.pid, 0)
                return {"error": f"timeout after {timeout:.0f} s"}
            time.sleep(0.01)
        seconds = time.perf_counter() - t0
        err = proc.stderr.read()
        code = os.waitstatus_to_exitcode(status)
        if code != 0:
            msg = err.strip().splitlines()[-1] if err.strip() else f"exit {code}"
            return {"error": msg.replace("fembsptet: ", ""), "exit": code}
        with open(stats_file) as f:
            st = json.load(f)
        st["wall_seconds"] = seconds
        st["peak_rss_mb"] = rusage.ru_maxrss / 1024.0
        return st


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="*")
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--markdown", default=None, help="also write the table as markdown here")
    args = ap.parse_args(argv)
    paths = []
    for m in args.models or [os.path.join(ROOT, "tests/data/paper"), os.path.join(ROOT, "tests/data/corpus")]:
        if os.path.isdir(m):
            paths += sorted(os.path.join(m, f) for f in os.listdir(m) if f.endswith(".off"))
        else:
            paths.append(m)
    if not tetgen_available():
        print("tetgen is not installed: run scripts/setup.sh", file=sys.stderr)
        return 2
    head = ("model", "ours", "s", "MB", "Steiner", "tets", "tetgen s", "MB", "Steiner", "tets",
            "time x", "Steiner x", "tets x")
    rows, ratios = [], {"time": [], "tets": [], "steiner": []}
    total = {"ours_tets": 0, "tg_tets": 0}
    for path in paths:
        name = os.path.splitext(os.path.basename(path))[0]
        ours = run_ours(path, args.timeout)
        try:
            tg = run_tetgen(read_surface(path), "pY", timeout=args.timeout)
            tg_row = (f"{tg.seconds:.3f}", f"{tg.peak_rss_mb:.0f}", tg.steiner_points, len(tg.mesh.tets))
        except BspTetError as exc:
            tg = None
            tg_row = ("fails", "", "", "")
            tg_err = str(exc).splitlines()[0][:60]
        if "error" in ours:
            row = (name, "ERROR: " + ours["error"][:90], "", "", "", "") + tg_row + ("", "", "")
        else:
            r = ["", "", ""]
            if tg is not None:
                rt = ours["seconds_core"] / max(tg.seconds, 1e-3)
                rk = ours["tets"] / max(len(tg.mesh.tets), 1)
                ratios["time"].append(rt)
                ratios["tets"].append(rk)
                total["ours_tets"] += ours["tets"]
                total["tg_tets"] += len(tg.mesh.tets)
                rs = (ours["steiner_points"] + 1) / (tg.steiner_points + 1)
                ratios["steiner"].append(rs)
                r = [f"{rt:.2f}", f"{ours['steiner_points']}/{tg.steiner_points}", f"{rk:.2f}"]
            row = (name, "valid", f"{ours['seconds_core']:.3f}", f"{ours['peak_rss_mb']:.0f}",
                   ours["steiner_points"], ours["tets"]) + tg_row + tuple(r)
        rows.append(tuple(map(str, row)))
        print(" | ".join(rows[-1]), flush=True)
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    summary = []
    if ratios["time"]:
        summary.append(f"models meshed by both: {len(ratios['time'])} of {len(rows)}")
        summary.append(f"median time ratio ours/tetgen -pY: {statistics.median(ratios['time']):.2f}")
        summary.append(f"median tets ratio: {statistics.median(ratios['tets']):.2f}; total tets ratio: "
                       f"{total['ours_tets'] / max(total['tg_tets'], 1):.2f}")
        summary.append(f"median (Steiner+1) ratio: {statistics.median(ratios['steiner']):.2f}")
    print("\n".join(summary))
    if args.markdown:
        from FemBspTet.atomic_file import atomic_output

        with atomic_output(args.markdown) as f:
            f.write("\n".join(lines + [""] + ["- " + s for s in summary]) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
