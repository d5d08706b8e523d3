# SPDX-License-Identifier: LGPL-2.1-or-later
"""Bad input and faults, through the command line as a user runs it.

The table below holds one bad input per row: how to make it, the exit code, the words of the
message that name the problem and the place. Every row also checks that no output file (and no
temporary file) is left. Then: --reorient, --write-intersections, the memory budget, --timeout
and Ctrl-C on a model that takes longer, a crash of the worker, and replays of the Python fuzz
findings pinned in tests/data/fuzz/.
"""

import json
import os
import signal
import struct
import subprocess
import time

import numpy as np
import pytest
from analytic_surfaces import lat_long_sphere
from conftest import DATA, corpus_path, paper_path

from FemBspTet.kernel.freecad_env import freecad_available

CUBE_POINTS = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
CUBE_TRIS = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4),
             (2, 6, 3), (3, 6, 7), (0, 4, 2), (2, 4, 6), (1, 3, 5), (3, 7, 5)]


def off_text(points, tris):
    lines = ["OFF", f"{len(points)} {len(tris)} 0"]
    lines += [" ".join(repr(float(c)) for c in p) for p in points]
    lines += ["3 " + " ".join(str(v) for v in t) for t in tris]
    return "\n".join(lines) + "\n"


def box(offset=0.0, size=1.0, base=0, flip=False):
    pts = [tuple(offset + size * c for c in p) for p in CUBE_POINTS]
    tris = [(a + base, c + base, b + base) if flip else (a + base, b + base, c + base)
            for a, b, c in CUBE_TRIS]
    return pts, tris


def two_boxes(first, second):
    p1, t1 = first
    p2, t2 = second
    return p1 + p2, t1 + t2


def write(name, content):
    """A maker: writes `content` (str or bytes) to tmp/name; returns the path."""
    def make(tmp):
        path = tmp / name
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content)
        return path
    return make


def write_off(name, points, tris):
    return write(name, off_text(points, tris))


def cube_with(points_extra=(), tris_extra=(), drop=(), replace=None, name="bad.off"):
    pts = list(CUBE_POINTS) + list(points_extra)
    tris = [t for i, t in enumerate(CUBE_TRIS) if i not in drop] + list(tris_extra)
    if replace:
        for i, t in replace.items():
            tris[i] = t
    return write_off(name, pts, tris)


def existing(path):
    return lambda tmp: path


def missing(tmp):
    return tmp / "nowhere.off"


def directory(tmp):
    d = tmp / "folder.off"
    d.mkdir()
    return d


def unreadable(tmp):
    if os.geteuid() != 0:
        path = tmp / "locked.off"
        path.write_text(off_text(*box()))
        path.chmod(0)
        return path
    # root reads any file: a file whose read fails (EIO) stands in for it.
    path = tmp / "locked.off"
    path.symlink_to("/proc/self/mem")
    return path


def binary_stl_truncated(tmp):
    path = tmp / "cut.stl"
    path.write_bytes(b"\0" * 80 + struct.pack("<I", 5) + b"\0" * 100)
    return path


def garbage(tmp):
    path = tmp / "noise.off"
    path.write_bytes(bytes(np.random.default_rng(7).integers(0, 256, 600, dtype=np.uint8)))
    return path


def cad_open_shell(tmp):
    from FemBspTet.kernel.freecad_env import import_freecad

    import_freecad()
    import Part

    path = tmp / "open_shell.step"
    Part.Shell(Part.makeBox(1, 2, 3).Faces[:5]).exportStep(str(path))
    return path


def cad_garbage(tmp):
    path = tmp / "junk.step"
    path.write_text("ISO-10303-21;\nHEADER;\nthis is not STEP\n")
    return path


def big_surface(tmp):
    """A closed surface of 20000 triangles: a latitude/longitude sphere."""
    path = tmp / "big.off"
    pts, tris = lat_long_sphere(101, 100)
    path.write_text(off_text(pts, tris))
    return path


P, T = box()
TABLE = [
    # id, maker, extra args, exit code, words naming the problem, words naming the place
    ("missing file", missing, [], 2, ["file not found"], ["nowhere.off"]),
    ("a directory", directory, [], 2, ["is a directory"], ["folder.off"]),
    ("unreadable file", unreadable, [], 2, ["cannot read the file"], ["locked.off"]),
    ("unknown format", write("model.xyz", "1 2 3\n"), [], 2,
     ["unknown input format '.xyz'"], ["model.xyz"]),
    ("garbage bytes", garbage, [], 2, ["not an OFF file"], ["noise.off", "line 1"]),
    ("truncated OFF", write("short.off", "OFF\n8 12 0\n0 0 0\n1 0 0\n"), [], 2,
     ["expected 8 vertices", "ends after 2"], ["short.off", "end of file"]),
    ("truncated binary STL", binary_stl_truncated, [], 2,
     ["truncated binary STL", "5 triangles"], ["cut.stl"]),
    ("truncated ASCII STL", write("cut_ascii.stl", "solid x\nfacet normal 0 0 1\nouter loop\n"
                                  "vertex 0 0 0\nvertex 1 0 0\n"), [], 2,
     ["ends inside facet 0"], ["cut_ascii.stl", "line 5"]),
    ("empty file", write("empty.off", ""), [], 2, ["the file is empty"], ["empty.off"]),
    ("blank file", write("blank.obj", "\n  \n\t\n"), [], 2, ["the file is empty"], ["blank.obj"]),
    ("no triangles", write("zero.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), [], 2,
     ["declares 0 faces"], ["zero.off", "line 2"]),
    ("NaN coordinate", write_off("nan.off", P[:3] + [(1.0, float("nan"), 0.0)] + P[4:], T), [], 2,
     ["non-finite coordinate"], ["nan.off", "vertex 3", "line 6"]),
    ("infinite coordinate", write("inf.obj", "v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n"), [], 2,
     ["non-finite coordinate"], ["inf.obj", "vertex 2", "line 2"]),
    ("index out of range", write_off("range.off", P, T[:2] + [(2, 6, 9)] + T[3:]), [], 2,
     ["vertex index 9, which is out of range", "valid indices 0..7"], ["range.off", "face 2"]),
    ("negative index", write_off("neg.off", P, T[:4] + [(0, -1, 4)] + T[5:]), [], 2,
     ["negative vertex index -1"], ["neg.off", "face 4"]),
    ("OBJ index 0", write("zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), [], 2,
     ["OBJ indices start at 1"], ["zero_index.obj", "line 4"]),
    ("polygon face", write("quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"), [], 2,
     ["only triangles are supported"], ["quad.off", "face 0"]),
    ("degenerate: collinear", cube_with([(0.5, 0.0, 0.0)], [(0, 8, 1)]), [], 2,
     ["degenerate", "collinear"], ["bad.off", "triangle 12"]),
    ("degenerate: repeated vertex", cube_with(replace={3: (5, 7, 7)}), [], 2,
     ["degenerate", "same point"], ["bad.off", "triangle 3"]),
    ("duplicate triangle", cube_with([(1.0, 1.0, 1.0)], [(3, 6, 8)]), [], 2,
     ["duplicates triangle 7"], ["bad.off", "triangle 12"]),
    ("open edges", cube_with(drop={11}), [], 2,
     ["used by only one triangle", "open", "3 open edges"], ["bad.off", "edge (", "triangle"]),
    ("non-manifold edge", cube_with([(0.5, -1.0, 0.5), (0.5, -1.0, -0.5)],
                                    [(0, 1, 8), (0, 8, 9), (0, 9, 1), (1, 9, 8)]), [], 2,
     ["non-manifold edge", "shared by 4 triangles"], ["bad.off", "edge (0 1)"]),
    ("non-manifold vertex", write_off("pinch.off", *two_boxes(box(), box(1.0, 1.0, 8))), [], 2,
     ["non-manifold vertex", "pinches"], ["pinch.off", "vertex 7 (1, 1, 1)"]),
    ("inconsistent orientation", cube_with(replace={4: (0, 4, 1)}), [], 2,
     ["inconsistent", "--reorient"], ["bad.off", "triangles 0 and 4", "edge (0 1)"]),
    ("inward-facing shell", write_off("inward.off", *box(flip=True)), [], 2,
     ["faces inward", "--reorient"], ["inward.off", "triangle 0"]),
    ("solid inside a solid", write_off("nested.off", *two_boxes(box(0, 4), box(1, 1, 8))), [], 2,
     ["lies inside", "faces outward"], ["nested.off", "triangle 12"]),
    ("self-intersection: overlapping boxes",
     write_off("overlap.off", *two_boxes(box(0, 2), box(1, 2, 8))), [], 2,
     ["intersects itself", "pairs of triangles", "--write-intersections"],
     ["overlap.off", "triangles"]),
    ("self-intersection: fold", existing(corpus_path("cube_with_fold")), [], 2,
     ["intersects itself", "11 pairs"], ["cube_with_fold.off", "triangles 21 and 22"]),
    ("corpus: duplicate shells", existing(corpus_path("openscad-nonmanifold-crash")), [], 2,
     ["degenerate"], ["openscad-nonmanifold-crash.off", "triangle 1359"]),
    ("corpus: inconsistent orientation", existing(corpus_path("td_spike-1-10")), [], 2,
     ["inconsistent"], ["td_spike-1-10.off", "triangles 0 and 8"]),
    ("corpus: inward-facing", existing(corpus_path("engine_bracket")), [], 2,
     ["faces inward"], ["engine_bracket.off", "triangle 0"]),
    ("memory budget (estimate)", big_surface, ["--max-memory", "150M"], 2,
     ["estimated", "memory budget", "--max-memory"], ["big.off", "20000 triangles"]),
    ("bad --max-memory", existing(paper_path("schoenhardt")), ["--max-memory", "lots"], 2,
     ["cannot read 'lots' as a size"], ["--max-memory"]),
    ("bad --timeout", existing(paper_path("schoenhardt")), ["--timeout", "-1"], 2,
     ["--timeout must be a positive number"], ["--timeout"]),
    ("unknown output format", existing(paper_path("schoenhardt")), ["-o", "{tmp}/x.docx"], 2,
     ["unknown output format '.docx'"], ["x.docx"]),
    ("missing output folder", existing(paper_path("schoenhardt")), ["-o", "{tmp}/no/x.vtu"], 2,
     ["output directory does not exist"], ["no"]),
    ("CAD: garbage STEP", cad_garbage, [], 2, ["not a readable STEP file"], ["junk.step"]),
    ("CAD: open shell, not a solid", cad_open_shell, [], 2, ["no solid"], ["open_shell.step"]),
]


def run_cli(cli, *args, timeout=300):
    return subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=timeout)


def leftovers(folder, keep=()):
    """Files in `folder` other than the inputs in `keep` (outputs, temporary files)."""
    names = set()
    for root, dirs, files in os.walk(folder):
        for n in files + dirs:
            full = os.path.join(root, n)
            if full not in keep:
                names.add(os.path.relpath(full, folder))
    return sorted(names)


@pytest.mark.parametrize("row", TABLE, ids=[r[0] for r in TABLE])
def test_bad_input_is_named_and_nothing_is_written(cli, tmp_path, row):
    name, make, extra, code, problem_words, place_words = row
    if name.startswith("CAD") and not freecad_available():
        pytest.skip("FreeCAD is not installed")
    inputs = tmp_path / "in"
    inputs.mkdir()
    source = make(inputs)
    before = set(leftovers(tmp_path))
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    extra = [a.replace("{tmp}", str(out_dir)) for a in extra]
    outputs = [] if "-o" in extra else ["-o", out_dir / "mesh.vtu", "-o", out_dir / "mesh.inp"]
    r = run_cli(cli, "mesh", source, *outputs, "--stats-json", out_dir / "stats.json", *extra)
    assert r.returncode == code, r.stderr
    message = r.stderr
    assert "Traceback" not in message, message
    assert message.count("fembsptet:") >= 1
    for word in problem_words + place_words:
        assert word in message, f"{word!r} not in {message!r}"
    assert leftovers(out_dir) == [], "output or temporary files were left"
    assert set(leftovers(tmp_path)) - before <= {"out"}


def test_table_covers_at_least_25_bad_inputs():
    assert len(TABLE) >= 25
    assert len({row[0] for row in TABLE}) == len(TABLE)


def test_failed_run_keeps_the_previous_output(cli, tmp_path):
    out = tmp_path / "mesh.vtu"
    r = run_cli(cli, "mesh", paper_path("schoenhardt"), "-o", out, "--quiet")
    assert r.returncode == 0, r.stderr
    before = out.read_bytes()
    r = run_cli(cli, "mesh", corpus_path("cube_with_fold"), "-o", out, "--quiet")
    assert r.returncode == 2
    assert out.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["mesh.vtu"]


def test_reorient_repairs_orientation_and_meshes_validly(cli, tmp_path):
    out = tmp_path / "spike.vtu"
    stats = tmp_path / "s.json"
    r = run_cli(cli, "mesh", corpus_path("td_spike-1-10"), "-o", out, "--reorient", "--quiet",
                "--stats-json", stats)
    assert r.returncode == 0, r.stderr
    assert "re-oriented 10 triangle(s)" in r.stderr
    assert json.loads(stats.read_text())["flipped_triangles"] == 10
    # The mesh fills the re-oriented surface: check it against that surface, exactly.
    from FemBspTet.kernel import core
    from FemBspTet.io.surface_io import read_surface, write_surface
    from FemBspTet.io.volume_io import read_tet_mesh

    fixed, info = core.check_surface(read_surface(corpus_path("td_spike-1-10")), reorient=True)
    assert info["flipped_triangles"] == 10
    report = core.check_mesh(fixed, read_tet_mesh(str(out)))
    assert report["valid"], report["messages"]
    # An inward box becomes outward; a cavity written outward becomes a cavity.
    inward = tmp_path / "inward.off"
    inward.write_text(off_text(*box(flip=True)))
    r = run_cli(cli, "mesh", inward, "-o", tmp_path / "b.vtu", "--reorient", "--quiet")
    assert r.returncode == 0, r.stderr
    nested = tmp_path / "nested.off"
    nested.write_text(off_text(*two_boxes(box(0, 4), box(1, 1, 8))))
    surface, info = core.check_surface(read_surface(str(nested)), reorient=True)
    assert info["flipped_triangles"] == 12 and info["shells"] == 2
    assert core.signed_volume(surface) == pytest.approx(64 - 1)
    write_surface(str(tmp_path / "fixed.off"), surface)
    core.check_surface(read_surface(str(tmp_path / "fixed.off")))  # no error now


def test_write_intersections_writes_the_pairs_triangles(cli, tmp_path):
    from FemBspTet.kernel import core
    from FemBspTet.kernel.errors import SelfIntersectionError
    from FemBspTet.io.surface_io import read_surface

    src = tmp_path / "overlap.off"
    src.write_text(off_text(*two_boxes(box(0, 2), box(1, 2, 8))))
    view = tmp_path / "pairs.ply"
    r = run_cli(cli, "mesh", src, "-o", tmp_path / "o.vtu", "--write-intersections", view)
    assert r.returncode == 2
    assert f"to {view}" in r.stderr
    with pytest.raises(SelfIntersectionError) as info:
        core.check_surface(read_surface(str(src)))
    pairs = info.value.pairs
    assert info.value.complete and len(pairs) > 0
    assert (pairs[:, 0] < 12).all() and (pairs[:, 1] >= 12).all()  # one of each box
    written = read_surface(str(view))
    involved = np.unique(pairs)
    assert sorted(written.face_tags.tolist()) == involved.tolist()
    original = read_surface(str(src))
    for tag, tri in zip(written.face_tags, written.triangles):
        assert np.array_equal(written.points[tri], original.points[original.triangles[tag]])
    assert not (tmp_path / "o.vtu").exists()
    # An unknown format for the file is refused before any work.
    r = run_cli(cli, "mesh", src, "-o", tmp_path / "o.vtu", "--write-intersections",
                tmp_path / "pairs.docx")
    assert r.returncode == 2 and "--write-intersections" in r.stderr


def test_python_api_raises_typed_errors_with_codes():
    from FemBspTet.kernel import core
    from FemBspTet.kernel.errors import InputError
    from FemBspTet.kernel.mesh_types import Surface

    pts, tris = box()
    cases = {
        "open_boundary": Surface(pts, tris[:-1]),
        "inward_facing": Surface(*box(flip=True)),
        "non_finite_coordinate": Surface([(np.inf, 0, 0)] + pts[1:], tris),
        "bad_argument": Surface(pts, [(0, 1, 99)] + tris[1:]),
        "non_manifold": Surface(*two_boxes(box(), box(1.0, 1.0, 8))),
    }
    for code, surface in cases.items():
        with pytest.raises(InputError) as info:
            core.tetrahedralize(surface)
        assert info.value.code == code, str(info.value)


def _timed_run(cli, args, signal_after=None, sig=signal.SIGINT):
    proc = subprocess.Popen([cli, *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    sent = None
    if signal_after is not None:
        time.sleep(signal_after)
        sent = time.monotonic()
        proc.send_signal(sig)
    out, err = proc.communicate(timeout=120)
    return proc.returncode, err, sent, time.monotonic()


# About 30 s on the reference machine (906 triangles on one plane; spot took 15 s before the
# Delaunay seed of the BSP, 1.2 s after).
SLOW_MODEL = corpus_path("thingi10k_112932")


def test_timeout_stops_within_a_second_and_writes_nothing(cli, tmp_path):
    out = tmp_path / "slow.vtu"
    start = time.monotonic()
    code, err, _, end = _timed_run(cli, ["mesh", SLOW_MODEL, "-o", out, "-o", tmp_path / "s.node",
                                         "--stats-json", tmp_path / "st.json", "--quiet",
                                         "--timeout", "2"])
    assert code == 124, err
    assert "time limit of 2 s (--timeout)" in err and "no output was written" in err
    # 2 s of work, the start-up of Python, and less than a second to stop.
    assert end - start < 2 + 3.0, end - start
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_ctrl_c_stops_within_a_second_and_writes_nothing(cli, tmp_path, sig):
    out = tmp_path / "slow.vtu"
    code, err, sent, end = _timed_run(cli, ["mesh", SLOW_MODEL, "-o", out, "--quiet"],
                                      signal_after=2.5, sig=sig)
    assert code == 130, err
    assert "interrupted" in err and "no output was written" in err
    assert end - sent < 1.0, end - sent
    assert os.listdir(tmp_path) == []


def test_worker_crash_is_reported_and_temporaries_removed(tmp_path):
    from FemBspTet.io.atomic_file import atomic_output
    from FemBspTet.kernel.errors import InternalError
    from FemBspTet.cli.supervisor import Limits, run_supervised

    target = tmp_path / "out.vtu"

    def crash():
        with atomic_output(str(target)) as f:
            f.write("partial")
            f.flush()
            # The default action: a hard crash (FreeCAD, if a test loaded it into this process,
            # turns SIGSEGV into an exception).
            signal.signal(signal.SIGSEGV, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGSEGV)
        return 0

    with pytest.raises(InternalError) as info:
        run_supervised(crash, Limits(), outputs=[str(target)])
    assert "crashed (SIGSEGV)" in str(info.value)
    assert os.listdir(tmp_path) == []
    # A job's own exit code passes through.
    assert run_supervised(lambda: 3, Limits()) == 3


def test_memory_watch_stops_a_run_over_budget(tmp_path):
    from FemBspTet.kernel.errors import MemoryBudgetError
    from FemBspTet.cli.supervisor import Limits, run_supervised

    def hog():
        block = bytearray(400 << 20)  # 400 MiB, touched
        for i in range(0, len(block), 4096):
            block[i] = 1
        time.sleep(30)
        return 0

    start = time.monotonic()
    with pytest.raises(MemoryBudgetError) as info:
        run_supervised(hog, Limits(max_memory=200 << 20))
    assert time.monotonic() - start < 10
    assert "more than the memory budget of 200.0 MiB" in str(info.value)


def test_sizes_and_estimates():
    from FemBspTet.kernel.errors import InputError
    from FemBspTet.kernel.memory_budget import estimate_peak_bytes, parse_size

    assert parse_size("4G") == 4 << 30 and parse_size("512M") == 512 << 20
    assert parse_size("1.5GiB") == 3 << 29 and parse_size("1000") == 1000
    for bad in ("", "G", "-1G", "4X", "nan"):
        with pytest.raises(InputError):
            parse_size(bad)
    small, big = estimate_peak_bytes(100, 200), estimate_peak_bytes(10000, 20000)
    assert small < big
    # The estimate stays above the typical measured peaks (docs/design/bad-input.md): spot, 5856
    # triangles, 36.5 MiB through the CLI; the 10^6-triangle bottle, 1.0 GiB in bsptet_mesh.
    assert estimate_peak_bytes(2930, 5856) > 37 << 20
    assert estimate_peak_bytes(503157, 1006310) > 1100 << 20
    # ... and a 10^6-triangle part is not refused up front on a 24 GiB machine.
    assert estimate_peak_bytes(503157, 1006310) < 8 << 30


FUZZ_DIR = os.path.join(DATA, "fuzz")


@pytest.mark.parametrize("name", sorted(os.listdir(FUZZ_DIR)) if os.path.isdir(FUZZ_DIR) else [])
def test_pinned_python_fuzz_findings(name):
    """Inputs the Python reader fuzzer found (scripts/fuzz_python_readers.py): only typed errors,
    and no numpy RuntimeWarning (an invalid cast means a silently wrong value)."""
    import warnings

    from FemBspTet.kernel.errors import InputError
    from FemBspTet.io.surface_io import read_surface
    from FemBspTet.io.volume_io import read_tet_mesh

    path = os.path.join(FUZZ_DIR, name)
    reader = read_surface if os.path.splitext(name)[1] in (".off", ".stl", ".obj", ".ply") \
        else read_tet_mesh
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        try:
            reader(path)
        except InputError:
            pass


def test_internal_error_of_the_core_is_reported_cleanly(cli, tmp_path):
    """plate_holes: the core of this branch's base ended in an internal error (exit 1, a message
    that says it is our fault, nothing written); main's core meshes it, and then the mesh must be
    valid. The error path itself is tested with a test double below."""
    out = tmp_path / "plate.vtu"
    r = run_cli(cli, "mesh", corpus_path("plate_holes"), "-o", out, "--quiet")
    if r.returncode == 0:
        check = run_cli(cli, "check", corpus_path("plate_holes"), out)
        assert check.returncode == 0, check.stdout
        return
    assert r.returncode == 1, r.stderr
    assert "the mesher failed" in r.stderr and "please report it" in r.stderr
    assert "plate_holes.off" in r.stderr and "Traceback" not in r.stderr
    assert os.listdir(tmp_path) == []


def test_meshing_error_of_the_core_becomes_exit_1_and_no_file(tmp_path, monkeypatch, capsys):
    """The core's MeshingError (an internal limit) through core.py and the CLI
    (in this process, without the supervisor): exit 1, a message saying it is a bug, no file."""
    from FemBspTet import _bsptet, cli

    def failing(*args, **kwargs):
        raise _bsptet.MeshingError("could not move the surface Steiner point (test double)")

    monkeypatch.setattr(_bsptet, "tetrahedralize", failing)
    out = tmp_path / "o.vtu"
    code = cli.main(["mesh", paper_path("schoenhardt"), "-o", str(out), "--quiet"], supervise=False)
    err = capsys.readouterr().err
    assert code == 1, err
    assert "the mesher failed" in err and "please report it" in err and "schoenhardt.off" in err
    assert os.listdir(tmp_path) == []


def test_error_codes_are_the_cores():
    """The Python ErrorCode enum and the core's (errors.h, bound as _bsptet.ErrorCode) are one
    table; every input error the core raises carries a member."""
    from FemBspTet import _bsptet
    from FemBspTet.kernel.errors import ErrorCode

    native = set(_bsptet.ErrorCode.__members__)
    ours = {c.value for c in ErrorCode}
    assert native <= ours and ours - native == {"memory_budget"}
    from FemBspTet.kernel import core
    from FemBspTet.kernel.errors import InputError
    from FemBspTet.kernel.mesh_types import Surface

    pts, tris = box()
    with pytest.raises(InputError) as info:
        core.tetrahedralize(Surface(pts, tris[:-1]))
    assert info.value.code is ErrorCode.OPEN_BOUNDARY and info.value.code == "open_boundary"
