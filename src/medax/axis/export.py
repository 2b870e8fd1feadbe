"""The ``axis.json`` record of a traced axis."""

from __future__ import annotations

from typing import Any

from medax.axis.result import MedialAxis
from medax.geometry.resolution import coordinate_resolution

#: a reversed (clockwise) region's side k is the file's side USER_SIDE[k]: reversal keeps
#: sides 0 and 2 and swaps 1 and 3 (``Region.build``)
USER_SIDE = (0, 3, 2, 1)


def axis_record(axis: MedialAxis) -> dict[str, Any]:
    """A JSON-ready dict: region, pair, points (B1 -> B2), spline, errors, counts.

    Side numbers (``constraints``, ``start_side``, ``end_side``) are the file's, also for a
    clockwise region that was reversed.

    The spline's ``weights`` (one per control point) are written when it is rational (the
    closed-form axis of arc constraints: conic pieces)."""
    diag = axis.diagonal
    spline: dict[str, Any] = {
        "degree": axis.spline.degree,
        "knots": axis.spline.knots.tolist(),
        "control_points": axis.spline.control_points.tolist(),
    }
    if axis.spline.weights is not None:
        spline["weights"] = axis.spline.weights.tolist()
    user = USER_SIDE if axis.region.reoriented else (0, 1, 2, 3)
    return {
        "region": axis.region.name,
        "pair": list(axis.pair),
        "method": axis.method,
        "constraints": [user[axis.roles.a1], user[axis.roles.a2]],
        "start_side": user[axis.roles.b1],
        "end_side": user[axis.roles.b2],
        "reoriented": axis.region.reoriented,
        "points": axis.points.tolist(),
        "space_points": axis.space_points.tolist(),
        "distances": axis.d1.tolist(),
        "t_start": axis.t_start,
        "t_end": axis.t_end,
        "spline": spline,
        "max_point_error": axis.max_point_error,
        "max_curve_error": axis.max_curve_error,
        "max_point_error_rel": axis.max_point_error / diag,
        "max_curve_error_rel": axis.max_curve_error / diag,
        "tol": axis.tol,
        "coordinate_resolution_rel": coordinate_resolution(axis.space_points, diag),
        "diagonal": diag,
        "n_points": axis.n_points,
        "counts": {
            "points": axis.counts.points,
            "predictor_steps": axis.counts.predictor_steps,
            "corrector_iterations": axis.counts.corrector_iterations,
            "distance_evaluations": axis.counts.distance_evaluations,
            "refinement_rounds": axis.counts.refinements,
            "closed_form_pieces": axis.counts.closed_form_pieces,
        },
    }
