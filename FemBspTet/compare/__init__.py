"""Comparison with other meshers (TetGen, Gmsh), run as separate programs."""
