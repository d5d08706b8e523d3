# SPDX-License-Identifier: LGPL-2.1-or-later
"""Comparison with other meshers (TetGen, Gmsh), run as separate programs."""
