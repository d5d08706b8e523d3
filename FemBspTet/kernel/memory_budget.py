# SPDX-License-Identifier: LGPL-2.1-or-later
"""Memory budget of a meshing run: an estimate before it starts, sizes as people write them.

    from FemBspTet.kernel.memory_budget import estimate_peak_bytes, parse_size, require_within_budget
    budget = parse_size("4G")                         # 4 * 2**30 bytes
    require_within_budget(surfaces, budget)           # MemoryBudgetError if the estimate exceeds it

The estimate is the typical peak with margin: about 1 to 3 KiB per input triangle measured from
10^3 to 10^6 triangles (``docs/design/bad-input.md``), taken as 4 KiB, plus the
interpreter's share. The BSP's size depends on the geometry, not only on the counts (inputs
whose triangles cross many seed tets reach tens of KiB per triangle), so it is only a first
filter: the supervised CLI also watches the run's real resident memory against the same budget
(:mod:`FemBspTet.cli.supervisor`) and stops it if it goes over. An envelope over those worst cases
(80 KiB per triangle) would refuse every input above a few 10^5 triangles on a 24 GiB
machine, although 10^6 triangles take about 1 GiB.
"""

import math
import re

from .errors import InputError, MemoryBudgetError

__all__ = ["estimate_peak_bytes", "parse_size", "default_budget", "require_within_budget",
           "format_bytes"]

#: Fixed cost of a run: the Python interpreter, numpy, the core's tables (bytes).
BASE_BYTES = 96 << 20
#: Typical peak per input triangle with margin (bytes); see docs/design/bad-input.md. The measured
#: peak grows no faster than the triangle count (memory exponents 0.85 to 0.97, 10^4 to 10^6).
BYTES_PER_TRIANGLE = 4 << 10

_UNITS = {"": 1, "b": 1, "k": 1 << 10, "kb": 1 << 10, "kib": 1 << 10, "m": 1 << 20, "mb": 1 << 20,
          "mib": 1 << 20, "g": 1 << 30, "gb": 1 << 30, "gib": 1 << 30, "t": 1 << 40, "tb": 1 << 40,
          "tib": 1 << 40}


def estimate_peak_bytes(n_points, n_triangles):
    """Estimated peak memory (bytes) of meshing a surface of ``n_triangles`` triangles."""
    n = max(int(n_triangles), 1)
    return int(BASE_BYTES + BYTES_PER_TRIANGLE * n + 64 * max(int(n_points), 0))


def format_bytes(n):
    """``1536`` -> ``"1.5 KiB"``."""
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024.0
    return f"{n:.1f} TiB"  # pragma: no cover


def parse_size(text, option="size"):
    """``"4G"``, ``"512M"``, ``"1.5GiB"``, ``"1000000"`` -> bytes (binary units). InputError if not."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([A-Za-z]*)\s*", str(text))
    if not match or match.group(2).lower() not in _UNITS:
        raise InputError(f"{option}: cannot read {text!r} as a size; write e.g. 4G, 512M or 2GiB")
    value = float(match.group(1)) * _UNITS[match.group(2).lower()]
    if not math.isfinite(value) or value < 1:
        raise InputError(f"{option} must be at least one byte, got {text!r}")
    return int(value)


def default_budget():
    """The memory available now (``MemAvailable`` of /proc/meminfo), or None where unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def require_within_budget(surfaces, budget, where=None):
    """Raises :class:`MemoryBudgetError` if meshing ``surfaces`` (one after the other) is
    estimated to need more than ``budget`` bytes. The largest surface decides (the runs do not
    overlap), plus the meshes kept so far (small next to a BSP)."""
    if budget is None:
        return
    worst = max((estimate_peak_bytes(len(s.points), len(s.triangles)) for s in surfaces), default=0)
    if worst > budget:
        biggest = max(surfaces, key=lambda s: len(s.triangles))
        raise MemoryBudgetError(
            f"the surface has {len(biggest.triangles)} triangles: meshing it is estimated to need "
            f"about {format_bytes(worst)}, more than the memory budget of {format_bytes(budget)} "
            "(--max-memory, default: the memory available now); nothing was done. Raise the "
            "budget, free memory, mesh it in pieces within the budget (--out-of-core), or mesh "
            "a coarser tessellation (--size for CAD input)",
            where=where or (biggest.source or None), estimate=worst, budget=budget)
