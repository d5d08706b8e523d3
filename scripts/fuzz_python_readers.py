#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Time-boxed random-mutation fuzzing of the Python readers.

    scripts/fuzz_python_readers.py [--seconds 60] [--seed 1] [--findings DIR]

Seeds: the paper polyhedra, small corpus models, and the same surfaces and a small tet mesh
written in every format we read (OFF, STL ASCII and binary, OBJ, PLY ASCII and binary; VTU, MSH,
INP, TetGen .node/.ele, Medit .mesh). Each round picks a seed, mutates its bytes (bit flips, byte
and chunk insertions, deletions and copies, truncation, numbers replaced by extreme ones, splices
of two seeds) and reads the result with read_surface or read_tet_mesh.

A finding is anything but a normal return or an InputError: another exception (numpy's
RuntimeWarnings count: an invalid cast means a silently wrong value), a reader taking
more than --per-input seconds (a hang), or a returned mesh that breaks its contract (non-finite
coordinates, indices out of range, wrong shapes). Each finding is saved in --findings with its
traceback; pin it in tests/data/fuzz/ (tests/test_bad_input.py replays that folder) and fix the
cause. Prints the number of inputs run; exits 1 if there was a finding. Deterministic for a seed
(up to where the time box ends).
"""

import argparse
import os
import random
import shutil
import signal
import struct
import sys
import tempfile
import time
import traceback
import warnings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402

from FemBspTet.kernel.errors import InputError  # noqa: E402
from FemBspTet.kernel.mesh_types import Surface, TetMesh  # noqa: E402
from FemBspTet.io.surface_io import read_surface, write_surface  # noqa: E402
from FemBspTet.io.volume_io import read_tet_mesh, write_tet_mesh  # noqa: E402

SURFACE_EXT = (".off", ".stl", ".obj", ".ply")
VOLUME_EXT = (".vtu", ".msh", ".inp", ".node", ".ele", ".mesh")
INTERESTING = [b"-1", b"0", b"nan", b"inf", b"-inf", b"1e308", b"-1e-320", b"4294967296",
               b"99999999999999999999", b"2147483648", b"3", b"4", b"10", b"1.5", b"\x00",
               b"\n", b" ", b"#", b"\xff\xff\xff\xff", b"\x00\x00\x00\x80", b"e", b"-"]


class Hang(Exception):
    pass


def _alarm(signum, frame):
    raise Hang()


def binary_ply(points, tris):
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face %d\n"
            "property list uchar int vertex_indices\nend_header\n" % (len(points), len(tris)))
    body = b"".join(struct.pack("<fff", *p) for p in points)
    body += b"".join(struct.pack("<Biii", 3, *t) for t in tris)
    return head.encode("ascii") + body


def make_seeds(folder):
    """Writes the seed files into `folder`; returns [(path, kind)], kind 'surface' or 'volume'."""
    seeds = []
    sources = [os.path.join(ROOT, "tests", "data", "paper", n + ".off")
               for n in ("schoenhardt", "dented_box", "box_with_hole")]
    sources += [os.path.join(ROOT, "tests", "data", "corpus", n + ".off")
                for n in ("cube", "star", "step", "tinytorus")]
    for i, src in enumerate(sources):
        surface = read_surface(src)
        base = os.path.join(folder, f"s{i}")
        shutil.copy(src, base + ".off")
        seeds.append((base + ".off", "surface"))
        write_surface(base + ".obj", surface)
        write_surface(base + ".ply", Surface(surface.points, surface.triangles,
                                             np.arange(len(surface.triangles)) % 3))
        write_surface(base + ".stl", surface)
        write_surface(base + "_ascii.stl", surface, ascii=True)
        with open(base + "_bin.ply", "wb") as f:
            f.write(binary_ply(surface.points.tolist(), surface.triangles.tolist()))
        seeds += [(base + e, "surface") for e in (".obj", ".ply", ".stl", "_ascii.stl", "_bin.ply")]
    pts = np.array([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)], dtype=float)
    mesh = TetMesh(pts, np.array([(0, 1, 2, 3), (1, 2, 3, 4)]))
    from FemBspTet.kernel.core import to_second_order

    for order, m in ((1, mesh), (2, to_second_order(mesh))):
        for ext in (".vtu", ".msh", ".inp", ".node", ".mesh"):
            path = os.path.join(folder, f"v{order}{ext}")
            write_tet_mesh(path, m)
            seeds.append((path, "volume"))
            if ext == ".node":
                seeds.append((path[:-5] + ".ele", "volume"))
    return seeds


def mutate(rng, data, other):
    data = bytearray(data)
    for _ in range(rng.randint(1, 6)):
        op = rng.randrange(9)
        n = len(data)
        if op == 0 and n:  # flip bits
            i = rng.randrange(n)
            data[i] ^= 1 << rng.randrange(8)
        elif op == 1:  # insert an interesting token
            i = rng.randrange(n + 1)
            data[i:i] = rng.choice(INTERESTING)
        elif op == 2 and n:  # delete a chunk
            i = rng.randrange(n)
            del data[i:i + rng.randint(1, 64)]
        elif op == 3 and n:  # duplicate a chunk
            i = rng.randrange(n)
            data[i:i] = data[i:i + rng.randint(1, 128)]
        elif op == 4 and n:  # truncate
            del data[rng.randrange(n):]
        elif op == 5 and n:  # replace a number-like token
            i = rng.randrange(n)
            j = i
            while j < n and data[j:j + 1] not in (b" ", b"\n", b"\t", b"\r"):
                j += 1
            data[i:j] = rng.choice(INTERESTING)
        elif op == 6 and n:  # random byte
            data[rng.randrange(n)] = rng.randrange(256)
        elif op == 7 and other:  # splice another seed in
            i, j = rng.randrange(n + 1), rng.randrange(len(other))
            data[i:] = other[j:j + rng.randint(1, 512)] + data[i:]
        elif op == 8 and n >= 4:  # overwrite 4 bytes with an extreme integer (binary counts)
            i = rng.randrange(n - 3)
            data[i:i + 4] = struct.pack("<I", rng.choice([0, 1, 3, 0x7FFFFFFF, 0xFFFFFFFF]))
    return bytes(data)


def check_contract(result, kind):
    if kind == "surface":
        assert isinstance(result, Surface)
        assert result.points.ndim == 2 and result.points.shape[1] == 3
        assert result.triangles.ndim == 2 and result.triangles.shape[1] == 3
        assert np.isfinite(result.points).all(), "non-finite coordinates returned"
        assert len(result.triangles) > 0
        assert result.triangles.min() >= 0 and result.triangles.max() < len(result.points)
    else:
        assert isinstance(result, TetMesh)
        assert result.tets.ndim == 2 and result.tets.shape[1] in (4, 10)
        assert np.isfinite(result.points).all(), "non-finite coordinates returned"
        if len(result.tets):
            assert result.tets.min() >= 0 and result.tets.max() < len(result.points)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--per-input", type=float, default=10.0, help="seconds before a hang")
    ap.add_argument("--findings", default=os.path.join(ROOT, "build-fuzz", "findings",
                                                       "python_readers"))
    args = ap.parse_args()
    rng = random.Random(args.seed)
    warnings.simplefilter("error", RuntimeWarning)
    work = tempfile.mkdtemp(prefix="fembsptet-pyfuzz-")
    signal.signal(signal.SIGALRM, _alarm)
    runs = typed = ok = 0
    findings = []
    try:
        seeds = make_seeds(work)
        blobs = [(p, k, open(p, "rb").read()) for p, k in seeds]
        end = time.monotonic() + args.seconds
        while time.monotonic() < end:
            path, kind, data = rng.choice(blobs)
            other = rng.choice(blobs)[2]
            ext = os.path.splitext(path)[1]
            case = os.path.join(work, "case" + ext)
            mutated = mutate(rng, data, other)
            if ext in (".node", ".ele"):  # the pair: mutate this one, copy the seed's partner
                partner_ext = ".ele" if ext == ".node" else ".node"
                shutil.copy(path[: -len(ext)] + partner_ext, case[: -len(ext)] + partner_ext)
            with open(case, "wb") as f:
                f.write(mutated)
            reader = read_surface if kind == "surface" else read_tet_mesh
            runs += 1
            try:
                signal.setitimer(signal.ITIMER_REAL, args.per_input)
                try:
                    result = reader(case)
                finally:
                    signal.setitimer(signal.ITIMER_REAL, 0)
                check_contract(result, kind)
                ok += 1
            except InputError:
                typed += 1
            except Exception as exc:  # noqa: BLE001 - this is what we look for
                os.makedirs(args.findings, exist_ok=True)
                name = os.path.join(args.findings, f"finding-{len(findings):03d}{ext}")
                with open(name, "wb") as f:
                    f.write(mutated)
                with open(name + ".txt", "w") as f:
                    f.write(f"seed file {os.path.basename(path)}\n")
                    f.write("".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))
                findings.append(name)
                print(f"FINDING {name}: {type(exc).__name__}: {exc}"[:300], flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"python_readers: {runs} inputs in {args.seconds:g} s (seed {args.seed}): {ok} read, "
          f"{typed} typed InputError, {len(findings)} findings")
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
