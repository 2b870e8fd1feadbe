"""``medax axis``: trace the medial axis of a region read from a regions JSON file."""

from __future__ import annotations

import argparse
import logging
from collections.abc import Sequence
from typing import Any

from medax import tolerances
from medax.cli.options import check_tol
from medax.cli.outputs import JSON_SUFFIXES, Output, check_outputs
from medax.errors import InputError

log = logging.getLogger(__name__)
AXIS_PLOTS = (".png", ".svg")
PAIR_CHOICES = {"0,2": [(0, 2)], "1,3": [(1, 3)], "both": [(0, 2), (1, 3)]}


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "axis",
        help="medial axis of a 4-sided region",
        description="Trace the product-oriented medial axis of a 4-sided region: the curve "
        "equidistant from one pair of opposite sides (the constraints), from one side of the "
        "other pair to the other. Writes the points and the fitted B-spline as JSON and "
        "optionally a plot.",
        epilog="example: medax axis regions.json --region wavy --pair both -o axis.json "
        "--plot axis.png",
    )
    p.add_argument("regions", help="regions JSON file (format: see medax/data/regions.json)")
    p.add_argument("--region", required=True, help="name of the region in the file")
    p.add_argument(
        "--pair",
        default="0,2",
        help="constraint sides: 0,2 | 1,3 | both (default 0,2)",
    )
    p.add_argument(
        "--tol",
        type=float,
        default=tolerances.CURVE_TOL,
        help=f"fitted curve tolerance relative to the diagonal (default {tolerances.CURVE_TOL:g})",
    )
    p.add_argument("--method", choices=("frame", "paper"), default="frame", help="tracer (frame)")
    p.add_argument("-o", "--output", help="axis JSON (one object, or a list for --pair both)")
    p.add_argument("--plot", help="plot file (.png or .svg)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from medax.axis import trace_axis
    from medax.geometry.region_io import length_unit, load_region_file, read_region
    from medax.geometry.resolution import coordinate_resolution, resolution_note
    from medax.io_utils import staged_outputs, write_json

    pairs = PAIR_CHOICES.get(args.pair.replace(" ", ""))
    if pairs is None:
        raise InputError(f"--pair must be 0,2 or 1,3 or both, got '{args.pair}'")
    check_tol(args.tol, "--tol", tolerances.MIN_CURVE_TOL)
    check_outputs(
        [Output("-o", args.output, JSON_SUFFIXES), Output("--plot", args.plot, AXIS_PLOTS)],
        {"regions file": args.regions},
    )
    region = read_region(args.regions, args.region)
    unit = length_unit(load_region_file(args.regions))
    if region.reoriented:
        log.warning("region '%s' was clockwise: sides reversed in place", region.name)
    axes = [trace_axis(region, pr, tol=args.tol, method=args.method) for pr in pairs]
    res = coordinate_resolution(region.boundary, region.diagonal)
    note = resolution_note(region.name, res, tolerances.POINT_TOL)
    if note:
        log.warning("%s", note)
    for a in axes:
        print(
            f"{region.name} pair {a.pair[0]},{a.pair[1]}: {a.n_points} points, "
            f"max |d1-d2| {a.max_point_error / a.diagonal:.2e} (points) "
            f"{a.max_curve_error / a.diagonal:.2e} (spline) x diagonal {a.diagonal:.6g}"
        )
    with staged_outputs() as out:  # all outputs or none
        if args.output is not None:
            data = axis_document(axes, unit)
            write_json(out.path(args.output, "-o"), data[0] if len(data) == 1 else data, "-o")
        if args.plot is not None:
            from medax.viz.axis_plot import plot_axes

            plot_axes(region, axes, out.path(args.plot, "--plot"))
    for path in (args.output, args.plot):
        if path is not None:
            print(f"wrote {path}")
    return 0


def axis_document(axes: Sequence[Any], length_unit: str) -> list[dict[str, Any]]:
    """The ``axis.json`` records of ``axes``, each with the output header
    (:func:`medax.schemas.stamp`): the file holds one record, or the list of them."""
    from medax.axis.export import axis_record
    from medax.schemas import stamp

    return [
        stamp(
            "axis",
            axis_record(a),
            length_unit,
            {
                "curve_tol_rel": a.tol,
                "point_tol_rel": tolerances.POINT_TOL,
                "endpoint_tol_rel": tolerances.ENDPOINT_TOL,
            },
        )
        for a in axes
    ]
