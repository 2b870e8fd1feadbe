"""Named tolerances, all relative to a length scale (the region's or part's diagonal).

Pass them explicitly; these are the defaults.
"""

#: Equidistance of every traced axis point: ``|d1 - d2| <= POINT_TOL * diagonal``.
POINT_TOL = 1e-10
#: End points lie on B1/B2 within ``ENDPOINT_TOL * diagonal``.
ENDPOINT_TOL = 1e-12
#: The fitted B-spline is within ``CURVE_TOL * diagonal`` of the axis everywhere.
CURVE_TOL = 1e-6
#: Corners of a region must meet within ``CORNER_TOL * diagonal``.
CORNER_TOL = 1e-7
#: A side shorter than ``MIN_SIDE * diagonal`` is degenerate.
MIN_SIDE = 1e-9
#: Two faces are tangent along an edge when their normals differ by less than this (radians).
TANGENT_ANGLE = 1e-3
#: Smallest curve tolerance accepted (relative): about 4500 x the double epsilon. Measured on
#: ``wavy``: 1e-12 is met in 1.4 s; at 1e-13 the error stalls at 1.4e-12 (points) after 13 s
#: and 0.9 GB, and smaller asks only grow the work.
MIN_CURVE_TOL = 1e-12
#: Geometric tolerance of fillet simplification's construction (relative to the diagonal):
#: the smallest deviation tolerance ``simplify`` accepts.
BUILD_TOL = 1e-7
