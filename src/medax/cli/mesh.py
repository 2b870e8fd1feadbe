"""``medax mesh``: structured quad mesh of a region from a regions JSON file, or one
conforming quad mesh of a CAD part (STEP, IGES, BRep: :mod:`medax.cli.mesh_part`)."""

from __future__ import annotations

import argparse
import logging
import math
from pathlib import Path
from typing import Any

from medax import tolerances
from medax.cli import limits
from medax.cli.limits import check_estimate, region_estimate
from medax.cli.options import check_tol
from medax.cli.outputs import JSON_SUFFIXES, PLOT_SUFFIXES, Output, check_outputs
from medax.errors import InputError, MeshError

log = logging.getLogger(__name__)
#: inputs meshed as CAD parts (the extensions of :mod:`medax.cad.reader`)
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs", ".brep", ".brp")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "mesh",
        help="structured quad mesh of a 4-sided region, or quad mesh of a CAD part",
        description="Mesh a 4-sided region with quads whose node lines follow the distance "
        "ratio between opposite sides, blended from its values at boundary nodes at equal arc "
        "length (with --boundary ratio: curves of constant ratio, the middle one the medial "
        "axis) (default; "
        "rays of equal angle between two lines facing concentric arcs, so an annulus sector "
        "gets the exact polar grid), angle-weighted ratio curves on all line/arc pairs "
        "(angle), or the paper's recursive medial axes (paper). "
        "Writes .msh (Gmsh 4.1), .vtu, .inp (Abaqus) or .bdf (Nastran), a quality "
        "report and a plot. "
        "A CAD part (.step .stp .iges .igs .brep) is meshed as one conforming quad surface "
        "mesh: the medial grid on every 4-sided face (its outer wire has four corners once "
        "G1 edges are joined; no holes, no seam), with division counts from --size made "
        "equal on opposite sides across the part, and gmsh's quads (Frontal-Delaunay for "
        "quads, recombined) on the other faces on the same edge nodes. Groups: a physical "
        "surface per CAD face (face_I) and a physical curve per CAD edge (edge_J); region "
        "meshes get one per side (S0..S3). Parts print progress on stderr; their report "
        "gives, per face and over the part, Verdict's and gmsh's scaled Jacobian, the angles "
        "and whether each face got the medial grid (or why not).",
        epilog="examples: medax mesh regions.json --region wavy --divisions 16,16 -o wavy.vtu "
        "--report quality.json --plot wavy.png; "
        "medax mesh part.step --size 2 --simplify -o part.msh --report part.json "
        "--plot part.png",
    )
    p.add_argument(
        "regions",
        metavar="INPUT",
        help="regions JSON file (format: see medax/data/regions.json) or a CAD part "
        "(.step .stp .iges .igs .brep)",
    )
    p.add_argument("--region", help="name of the region in the file (default: the only one)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--size", type=float, help="target edge length (region or model units)")
    g.add_argument(
        "--divisions", help="quads along S0 and along S1: N1,N2 (or N for both; regions only)"
    )
    p.add_argument("--method", choices=("ratio", "angle", "paper"), default="ratio", help="(ratio)")
    p.add_argument(
        "--boundary",
        choices=("arclength", "ratio"),
        default=None,
        help="boundary nodes at equal arc length (arclength, the default, as gmsh "
        "transfinite) or at the ends of the constant-ratio curves (ratio); ratio and angle "
        "methods only (the paper's recursion places its own)",
    )
    p.add_argument(
        "--tol",
        type=float,
        default=None,
        help="node tolerance x diagonal (ratio, angle: 1e-6; interior nodes on free-form "
        "sides are interpolated where that is estimated within it, 0 solves every node; "
        "paper: the traced splines' tolerance, 1e-9)",
    )
    p.add_argument(
        "--faces",
        default="all",
        help="parts: the faces to mesh, 'all' or indices I,J,K (OCCT's face order, as in "
        "'medax classify'); default all",
    )
    p.add_argument(
        "--simplify",
        action="store_true",
        help="parts: simplify the fillets first (as 'medax simplify'), then mesh the result",
    )
    p.add_argument(
        "--all-gmsh",
        action="store_true",
        help="parts: mesh every face with gmsh (no medial grids), for comparison",
    )
    p.add_argument("-o", "--output", required=True, help="mesh file: .msh .vtu .inp .bdf")
    p.add_argument("--format", help="override the format: msh, vtu, abaqus, nastran")
    p.add_argument("--report", help="quality report (JSON)")
    p.add_argument("--plot", help="plot coloured by scaled Jacobian (.png, .svg, .pdf)")
    p.add_argument(
        "--smooth",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="regions: the quality pass after the grid (the default; Winslow's equations on "
        "the interior nodes, boundary nodes and exact polar grids kept), kept only where it "
        "lowers neither the minimum nor the 5th-percentile scaled Jacobian nor the smallest "
        "angle; --no-smooth: the medial grid as solved",
    )
    p.add_argument(
        "--allow-inverted",
        action="store_true",
        help="write the mesh even when quads are inverted (refused by default)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="run even when the peak memory estimated from the node count (regions: "
        "(N1+1)(N2+1); parts: surface area / size^2) exceeds the limit, "
        f"{limits.MEMORY_SHARE:g} x the available memory and at most "
        f"{limits.MAX_BYTES / limits.GB:g} GB (refused by default); estimates above "
        f"{limits.NOTE_BYTES / limits.GB:g} GB or {limits.NOTE_S:g} s are printed on stderr "
        "before the work",
    )
    p.set_defaults(run=run)


def parse_divisions(text: str) -> tuple[int, int]:
    """``"N1,N2"`` or ``"N"`` -> (n1, n2); InputError on anything else or counts below 1."""
    parts = [s.strip() for s in text.split(",")]
    try:
        values = [int(s) for s in parts]
    except ValueError:
        raise InputError(f"--divisions must be N1,N2 (integers), got '{text}'") from None
    if len(values) == 1:
        values = values * 2
    if len(values) != 2:
        raise InputError(f"--divisions must be N1,N2, got '{text}'")
    if min(values) < 1:
        raise InputError(f"--divisions must be at least 1, got '{text}'")
    return values[0], values[1]


def _region_name(path: str, name: str | None) -> str:
    from medax.geometry.region_io import load_region_file, region_names

    if name is not None:
        return name
    names = region_names(load_region_file(path))
    if len(names) != 1:
        raise InputError(f"{path}: give --region (regions: {', '.join(names) or 'none'})")
    return names[0]


def report(mesh: Any, time_s: float) -> dict[str, Any]:
    """The quality report: counts, divisions, method, time and the quality summary."""
    summary = mesh.quality().summary()
    return {
        "region": mesh.region.name,
        "method": mesh.method,
        "n1": mesh.n1,
        "n2": mesh.n2,
        "n_nodes": mesh.n_nodes,
        "n_quads": mesh.n_quads,
        "time_s": time_s,
        **summary,
        "solver": {k: v for k, v in mesh.info.items() if k != "time_s"},
    }


def run(args: argparse.Namespace) -> int:
    from medax.geometry.region_io import length_unit, load_region_file, read_region
    from medax.geometry.resolution import coordinate_resolution, resolution_note
    from medax.io_utils import staged_outputs, write_json
    from medax.mesh.export import format_from_path
    from medax.mesh.grouped_export import region_groups, write_grouped_mesh
    from medax.mesh.mesher import divisions_for_size, mesh_region
    from medax.schemas import stamp

    if Path(args.regions).suffix.lower() in CAD_SUFFIXES:
        from medax.cli.mesh_part import run_part

        if args.smooth is not None:
            raise InputError("--smooth and --no-smooth apply to regions, not to CAD parts")
        return run_part(args)
    # validate everything before any work, so bad input leaves no file behind
    check_outputs(
        [
            Output("-o", args.output, None),
            Output("--report", args.report, JSON_SUFFIXES),
            Output("--plot", args.plot, PLOT_SUFFIXES),
        ],
        {"regions file": args.regions},
    )
    if args.size is None and args.divisions is None:
        raise InputError("give --size or --divisions")
    if args.simplify or args.all_gmsh or args.faces != "all":
        raise InputError("--simplify, --all-gmsh and --faces apply to CAD parts, not regions")
    fmt = format_from_path(args.output, args.format)
    divisions = parse_divisions(args.divisions) if args.divisions is not None else None
    if args.size is not None and not (math.isfinite(args.size) and args.size > 0.0):
        raise InputError(f"--size must be positive, got {args.size}")
    if args.boundary is not None and args.method == "paper":
        raise InputError("--boundary applies to the ratio and angle methods, not to paper")
    if args.tol is not None:
        check_tol(args.tol, "--tol", tolerances.MIN_CURVE_TOL, zero_ok=args.method != "paper")
    region = read_region(args.regions, _region_name(args.regions, args.region))
    if divisions is not None:
        what, (n1, n2) = f"--divisions {divisions[0]},{divisions[1]}", divisions
    else:
        n1, n2 = divisions_for_size(region, args.size)
        what = f"--size {args.size:g} ({n1}x{n2} quads)"
    est = region_estimate(n1, n2, args.method, args.plot is not None)
    check_estimate(est, what, args.force)
    log.info("mesh: region '%s', %dx%d quads by the %s method", region.name, n1, n2, args.method)
    mesh = mesh_region(
        region,
        divisions=divisions,
        size=args.size,
        method=args.method,
        tol=args.tol,
        boundary=args.boundary or "arclength",
        allow_inverted=args.allow_inverted,
        smooth=args.smooth is not False,
    )
    time_s = float(mesh.info["time_s"])
    rep = report(mesh, time_s)
    res = coordinate_resolution(mesh.points, region.diagonal)
    rep["coordinate_resolution_rel"] = res
    rep = stamp(
        "mesh-report",
        rep,
        length_unit(load_region_file(args.regions)),
        {"node_tol_rel": float(mesh.info["tol"])},
        angle="deg",
        time="s",
    )
    note = resolution_note(region.name, res, args.tol or tolerances.CURVE_TOL)
    if note:
        log.warning("%s", note)
    sj = rep["scaled_jacobian"]
    print(
        f"{region.name}: {mesh.n1}x{mesh.n2} quads ({args.method}), {mesh.n_nodes} nodes, "
        f"{time_s:.3f} s; scaled Jacobian min {sj['min']:.3f} p5 {sj['p5']:.3f} mean "
        f"{sj['mean']:.3f}; {rep['n_inverted']} inverted"
    )
    if rep["n_inverted"] and not args.allow_inverted:
        raise MeshError(
            f"region '{region.name}': {rep['n_inverted']} of {mesh.n_quads} quads are inverted "
            "(scaled Jacobian <= 0); nothing written (--allow-inverted writes it anyway)"
        )
    with staged_outputs() as out:  # all outputs or none
        groups = region_groups(mesh.n1, mesh.n2)
        quality = mesh.quality().as_dict()
        target = out.path(args.output, "-o")
        write_grouped_mesh(target, mesh.points, mesh.quads, groups, quality, fmt)
        if args.report is not None:
            write_json(out.path(args.report, "--report"), rep, "--report")
        if args.plot is not None:
            from medax.viz.mesh_plot import plot_mesh

            plot_mesh(mesh, out.path(args.plot, "--plot"))
    for path in (args.output, args.report, args.plot):
        if path is not None:
            print(f"wrote {path}")
    return 0
