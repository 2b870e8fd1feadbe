"""``medax classify``: recognise fillets in a STEP/IGES/BRep part and trace their axes."""

from __future__ import annotations

import argparse
import logging
import math
from pathlib import Path
from typing import Any

from medax import tolerances
from medax.cli.options import check_tol
from medax.cli.outputs import JSON_SUFFIXES, Output, check_outputs
from medax.errors import InputError

log = logging.getLogger(__name__)
VIEW_SUFFIXES = (".png", ".svg")
STEP_SUFFIXES = (".step", ".stp")
VIEW3D_SUFFIXES = (".html", ".htm", ".json")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "classify",
        help="classify the faces of a CAD part (fillets, corner blends, supporting, protection)",
        description="Read a STEP/IGES/BRep part, heal it, classify its faces as the paper does "
        "(fillet, corner_blend, supporting, protection) and the edges of supporting faces "
        "(smooth, semi_smooth, non_smooth), and trace the medial axis of every edge fillet on "
        "its surface. Prints a summary; writes a JSON report and a shaded 3D view on request.",
        epilog="example: medax classify part.step --report classes.json --png view.png",
    )
    p.add_argument("part", help="CAD file: .step/.stp, .iges/.igs or .brep")
    p.add_argument("--report", help="JSON report (classes.json)")
    p.add_argument("--png", help="shaded 3D view coloured by class (.png or .svg)")
    p.add_argument(
        "--step",
        help="the (healed) part as STEP with each face coloured by class and named "
        "('fillet 12 r=2.5')",
    )
    p.add_argument(
        "--view3d",
        help="interactive 3D view: a self-contained HTML page (.html) or its data (.json, "
        "kind view3d) for medax batch's report",
    )
    p.add_argument(
        "--angle",
        type=float,
        default=tolerances.TANGENT_ANGLE,
        help=f"tangency tolerance in radians (default {tolerances.TANGENT_ANGLE:g})",
    )
    p.add_argument(
        "--tol",
        type=float,
        default=tolerances.CURVE_TOL,
        help=f"axis curve tolerance relative to the fillet's diagonal "
        f"(default {tolerances.CURVE_TOL:g})",
    )
    p.add_argument("--no-axes", action="store_true", help="do not trace the fillet axes")
    p.add_argument(
        "--view",
        default="28,-55",
        help="PNG view direction as ELEVATION,AZIMUTH in degrees (default 28,-55)",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from medax.io_utils import staged_outputs, write_json

    if not (math.isfinite(args.angle) and args.angle > 0.0):
        raise InputError(f"--angle {args.angle}: must be a positive number of radians")
    check_tol(args.tol, "--tol", tolerances.MIN_CURVE_TOL)
    try:
        elev, azim = (float(x) for x in args.view.split(","))
    except ValueError as err:
        raise InputError(f"--view must be ELEVATION,AZIMUTH in degrees, got '{args.view}'") from err
    check_outputs(
        [
            Output("--report", args.report, JSON_SUFFIXES),
            Output("--png", args.png, VIEW_SUFFIXES),
            Output("--step", args.step, STEP_SUFFIXES),
            Output("--view3d", args.view3d, VIEW3D_SUFFIXES),
        ],
        {"input part": args.part},
    )
    report, solids = classify_part(args.part, args.angle, args.tol, not args.no_axes)
    for line in summary_lines(report):
        print(line)
    with staged_outputs() as out:  # all outputs or none
        if args.report is not None:
            write_json(out.path(args.report, "--report"), report, "--report")
        if args.png is not None:
            tmp = out.path(args.png, "--png")
            render_solids(solids, tmp, title=Path(args.part).name, view=(elev, azim))
        if args.step is not None:
            write_classes_step(solids, out.path(args.step, "--step"), args.step)
        if args.view3d is not None:
            from medax.cad.view_data import classified_view, write_view

            model = classified_view(solids, Path(args.part).name)
            write_view(
                model, out.path(args.view3d, "--view3d"), report["unit"], report["tolerances"]
            )
    for path in (args.report, args.png, args.step, args.view3d):
        if path is not None:
            print(f"wrote {path}")
    return 0


def classify_part(
    path: str | Path,
    angle: float = tolerances.TANGENT_ANGLE,
    tol: float = tolerances.CURVE_TOL,
    axes: bool = True,
) -> tuple[dict[str, Any], list[Any]]:
    """Read, classify and (``axes``) trace; returns the report dict and ClassifiedSolids."""
    from medax.cad.classify import classify_solid
    from medax.cad.reader import read_part
    from medax.cad.report import ClassifiedSolid, part_report, trace_fillet_axes
    from medax.schemas import stamp

    part = read_part(path)
    solids = []
    for k, s in enumerate(part.solids):
        c = classify_solid(s, angle, source=part.source, unit=part.unit, index=k)
        log.info("classify: solid %d: %d faces, %d fillets", k, len(c.faces), len(c.fillets))
        solids.append(trace_fillet_axes(c, tol) if axes else ClassifiedSolid(c))
    report = part_report(solids, part.source, part.unit, part.file_unit, part.notes)
    tols = {"tangent_angle_rad": angle, "axis_curve_tol_rel": tol}
    return stamp("classify-report", report, part.unit, tols, angle="rad"), solids


def summary_lines(report: dict[str, Any]) -> list[str]:
    """Human-readable summary of a report (one line per solid, doubts, axis failures)."""
    lines = [f"{report['source']}: {n}" for n in report["notes"]]
    if report["file_unit"]:
        lines.append(
            f"{report['source']}: file unit {report['file_unit']}, lengths in {report['unit']}"
        )
    for sr in report["solids"]:
        s = sr["summary"]
        lines.append(
            f"{report['source']} solid {sr['solid']}: {s['faces']} faces: {s['fillet']} fillet, "
            f"{s['corner_blend']} corner_blend, {s['supporting']} supporting, "
            f"{s['protection']} protection; {s['axes']} axes traced"
        )
        for d in sr["doubts"]:
            lines.append(f"  doubt: face {d['face']}: {d['reason']}")
        for f in sr["fillets"]:
            if "axis_error" in f:
                lines.append(f"  no axis on fillet face {f['face']}: {f['axis_error']}")
    return lines


def write_classes_step(solids: list[Any], path: str | Path, label: str | Path) -> None:
    """The classified solids as STEP at ``path``, each face coloured by class and named
    (:func:`medax.cad.xcaf.class_styles`); ``label``: the file's name in messages."""
    from medax.cad.reader import quiet_occt
    from medax.cad.simplify.occ import compound
    from medax.cad.xcaf import class_styles, write_styled_step

    cls = [s.classification for s in solids]
    shape = cls[0].shape if len(cls) == 1 else compound([c.shape for c in cls])
    with quiet_occt():
        write_styled_step(shape, path, class_styles(cls), Path(label).stem, label)


def render_solids(
    solids: list[Any],
    path: str | Path,
    title: str = "",
    view: tuple[float, float] = (28.0, -55.0),
) -> Path:
    """Shaded view of classified solids with their axes, written atomically to ``path``."""
    from collections import Counter

    from medax.cad.tessellate import edge_polylines, mesh_faces
    from medax.io_utils import atomic_path
    from medax.viz.view3d import render_part

    faces: list[Any] = []
    edges: list[Any] = []
    axes: list[Any] = []
    counts: Counter[str] = Counter()
    for cs in solids:
        c = cs.classification
        for fm in mesh_faces(c):
            faces.append((c.faces[fm.index].cls.value, fm.points, fm.triangles))
        edges.extend(edge_polylines(c))
        axes.extend(a.region.embedding.evaluate(a.spline.sample(80)) for a in cs.axes.values())
        counts.update(f.cls.value for f in c.faces)
    with atomic_path(path) as tmp:
        render_part(faces, tmp, edges=edges, axes=axes, title=title, counts=dict(counts), view=view)
    return Path(path)
