# SPDX-License-Identifier: LGPL-2.1-or-later
"""The meshers we compare with, run as separate programs (TetGen, Gmsh; never linked) and
measured by our own code (wall time, peak memory of the process tree). Imports the kernel and io."""
