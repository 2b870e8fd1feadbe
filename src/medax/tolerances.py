"""Named tolerances, all relative to a length scale (the region's or part's diagonal).

Pass them explicitly; these are the defaults.
"""

POINT_TOL = 1e-10
"""Equidistance of every traced axis point: ``|d1 - d2| <= POINT_TOL * diagonal``."""
ENDPOINT_TOL = 1e-12
"""End points lie on B1/B2 within ``ENDPOINT_TOL * diagonal``."""
CURVE_TOL = 1e-6
"""The fitted B-spline is within ``CURVE_TOL * diagonal`` of the axis everywhere."""
CORNER_TOL = 1e-7
"""Corners of a region must meet within ``CORNER_TOL * diagonal``."""
MIN_SIDE = 1e-9
"""A side shorter than ``MIN_SIDE * diagonal`` is degenerate."""
TANGENT_ANGLE = 1e-3
"""Two faces are tangent along an edge when their normals differ by less (radians)."""
MIN_CURVE_TOL = 1e-12
"""Smallest curve tolerance accepted (relative): about 4500 x the double epsilon.

Measured on ``wavy``: 1e-12 is met in 1.4 s; at 1e-13 the error stalls at 1.4e-12 (points)
after 13 s and 0.9 GB, and smaller asks only grow the work.
"""
BUILD_TOL = 1e-7
"""Geometric tolerance of fillet simplification's construction (relative to the diagonal):
the smallest deviation tolerance ``simplify`` accepts."""
