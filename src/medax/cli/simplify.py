"""``medax simplify PART.step -o SIMPLE.step``: remove fillets, keep the shape.

Reads and classifies the part (``medax.cad``), simplifies every fillet it can (split along
the medial curve, merge the halves, rebuild, validate) and writes the result atomically.
Fillets that cannot be simplified are kept and listed with the reason in the report.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from medax.cli.classify import VIEW3D_SUFFIXES
from medax.cli.options import check_tol
from medax.cli.outputs import JSON_SUFFIXES, PLOT_SUFFIXES, Output, check_outputs
from medax.io_utils import staged_outputs, write_json
from medax.schemas import stamp

log = logging.getLogger(__name__)


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "simplify",
        help="remove fillets from a STEP solid without changing its shape",
        description="Split each fillet along its medial curve, merge the halves into the "
        "supporting faces, rebuild and validate the solid; write it as STEP, IGES or BRep (by "
        "the output's extension; STEP faces are coloured and named by merged group). Every "
        "output is checked before any work and all are written together or none.",
    )
    p.add_argument("part", help="input part (.step/.stp, .iges/.igs, .brep)")
    p.add_argument(
        "-o", "--output", required=True, help="output solid: .step/.stp, .iges/.igs or .brep"
    )
    p.add_argument("--report", help="JSON report (faces, blends removed/kept, validation)")
    p.add_argument("--png", help="before/after picture (.png, .svg or .pdf)")
    p.add_argument(
        "--view3d",
        help="interactive 3D view of the result, faces coloured by merged group: an HTML "
        "page (.html) or its data (.json, kind view3d)",
    )
    p.add_argument("--tol", type=float, default=1e-5, help="deviation tolerance x diagonal (1e-5)")
    p.add_argument(
        "--strict-volume",
        action="store_true",
        help="also keep the fillets whose merged faces OCCT's default mass properties "
        "(FreeCAD, CadQuery) would read as a volume change above 1e-6: the written file then "
        "measures right in those tools too, and fewer blends go (its fixed Gauss rules do not "
        "resolve a curvature jump inside a fitted face)",
    )
    p.set_defaults(run=run)


def colour_keys(report: dict[str, Any], n_before: int) -> tuple[list[int], list[int]]:
    """Colour key per face before and after (see :func:`medax.viz.before_after`)."""
    before = [-1] * n_before
    after = [-1] * report["faces_after"]
    for f in report["blends_removed"]:
        before[f] = -2
    kept = {b["face"] for b in report["blends_kept"]}
    for f in kept:
        before[f] = -3
    k = 0
    for g in report["face_groups"]:
        if not g["fillet_halves"]:
            if set(g["original_faces"]) & kept:
                after[g["new_face"]] = -3
            continue
        after[g["new_face"]] = k
        for f in g["original_faces"]:
            before[f] = k
        k += 1
    return before, after


def run(args: argparse.Namespace) -> int:
    from medax.cad.classify import classify_file
    from medax.cad.simplify import simplify, specs_from_classification
    from medax.cad.simplify.occ import compound
    from medax.cad.simplify.pipeline import BUILD_TOL, VOLUME_TOL
    from medax.cad.simplify.readback import read_back
    from medax.cad.simplify.step_out import SHAPE_SUFFIXES, shape_format, write_shape
    from medax.cad.xcaf import group_styles

    check_outputs(
        [
            Output("-o", args.output, tuple(SHAPE_SUFFIXES)),
            Output("--report", args.report, JSON_SUFFIXES),
            Output("--png", args.png, PLOT_SUFFIXES),
            Output("--view3d", args.view3d, VIEW3D_SUFFIXES),
        ],
        {"input part": args.part},
    )
    fmt = shape_format(args.output)
    check_tol(args.tol, "--tol", BUILD_TOL)

    def progress(msg: str) -> None:
        log.info("simplify: %s", msg)

    classes = classify_file(args.part)
    results = []
    for k, cls in enumerate(classes):
        specs = specs_from_classification(cls)
        n = len(specs.fillets) + len(specs.refused)
        progress(f"solid {k}: {len(cls.faces)} faces, {n} blends")
        results.append(
            simplify(
                cls.shape,
                specs,
                tol=args.tol,
                progress=progress,
                strict_volume=args.strict_volume,
            )
        )
    shape = results[0].shape if len(results) == 1 else compound([r.shape for r in results])
    report = _combine([r.report() for r in results])
    report["input"] = str(args.part)
    report["output"] = str(args.output)
    report["strict_volume"] = bool(args.strict_volume)
    tols = simplify_tolerances(args.tol)
    report = stamp("simplify-report", report, classes[0].unit, tols, time="s")
    with staged_outputs() as out:  # all outputs or none
        styles = group_styles([r.shape for r in results], [r.report() for r in results])
        staged = write_shape(
            shape, out.path(args.output, "-o"), fmt, styles, Path(args.output).stem, args.output
        )
        progress(f"reading {Path(args.output).name} back")
        diag = max(r.diagonal for r in results)
        report["written_file"] = read_back(
            staged, fmt, shape, args.tol * diag, name=args.output
        ).report()
        if args.report is not None:
            write_json(out.path(args.report, "--report"), report, "--report")
        if args.png is not None:
            _png(classes[0].shape, results[0], out.path(args.png, "--png"), Path(args.part).name)
        if args.view3d is not None:
            from medax.cad.view_data import simplified_view, write_view

            model = simplified_view(
                [r.shape for r in results], [r.report() for r in results], Path(args.part).name
            )
            write_view(model, out.path(args.view3d, "--view3d"), report["units"]["length"], tols)
    for k, r in enumerate(results):
        label = f"{args.part}" + (f" solid {k}" if len(results) > 1 else "")
        print(
            f"{label}: faces {r.faces_before} -> {r.faces_after}, "
            f"{len(r.blends_removed)} blends removed, {len(r.blends_kept)} kept, "
            f"valid {r.valid}, volume change {r.volume_rel_change:.1e}, "
            f"deviation {r.max_deviation / r.diagonal:.1e} x diagonal"
        )
        if abs(r.default_volume_rel_change) > VOLUME_TOL:
            print(
                f"note: OCCT's default mass properties (FreeCAD, CadQuery) give a volume "
                f"change of {r.default_volume_rel_change:+.1e} here: their fixed Gauss rules "
                "do not resolve the curvature jumps inside fitted merged faces (or the "
                "input's own faces); Gauss-Kronrod (BRepGProp.VolumePropertiesGK_s) measures "
                f"the {r.volume_rel_change:+.1e} above"
                + ("" if args.strict_volume else "; --strict-volume keeps such merges")
            )
    written = report["written_file"]
    dv_key = "default_integrator_volume_rel_change"
    if written["max_deviation"] > args.tol * diag:
        print(
            f"note: {Path(args.output).name} reads back up to {written['max_deviation']:.2g} "
            f"from the validated solid (volume {written[dv_key]:+.1e}), within "
            f"the input's own edge tolerances ({written['allowed_deviation']:.2g} allowed); "
            "a .brep output keeps it exact"
        )
    for path in (args.output, args.report, args.png, args.view3d):
        if path is not None:
            print(f"wrote {path}")
    return 0


def simplify_tolerances(tol: float | None = None) -> dict[str, float]:
    """The tolerances a simplification checks against (``tol``: the deviation's, default
    :data:`~medax.cad.simplify.pipeline.DEVIATION_TOL`), for the reports' header."""
    from medax import tolerances
    from medax.cad.simplify import pipeline

    return {
        "deviation_tol_rel": pipeline.DEVIATION_TOL if tol is None else tol,
        "volume_tol_rel": pipeline.VOLUME_TOL,
        "area_tol_rel": pipeline.AREA_TOL,
        "build_tol_rel": pipeline.BUILD_TOL,
        "tangent_angle_rad": tolerances.TANGENT_ANGLE,
    }


def _combine(reports: list[dict[str, Any]]) -> dict[str, Any]:
    """One report: the solid's own for one solid; for several, totals (faces, time), the
    worst values (validity, volume and area change, deviation) and each solid's report in
    ``solids`` (face indices are per solid)."""
    from medax.cad.simplify.reasons import reason_counts

    if len(reports) == 1:
        return dict(reports[0])
    worst_dv = max((r["volume_rel_change"] for r in reports), key=abs)
    worst_da = max((r["area_rel_change"] for r in reports), key=abs)
    worst_dev = max(reports, key=lambda r: r["max_deviation"]["relative_to_diagonal"])
    return {
        "faces_before": sum(r["faces_before"] for r in reports),
        "faces_after": sum(r["faces_after"] for r in reports),
        "blends_removed": [[k, f] for k, r in enumerate(reports) for f in r["blends_removed"]],
        "blends_found": sum(r["blends_found"] for r in reports),
        "blends_kept": [dict(b, solid=k) for k, r in enumerate(reports) for b in r["blends_kept"]],
        "kept_reasons": reason_counts(b["reason"] for r in reports for b in r["blends_kept"]),
        "valid": all(r["valid"] for r in reports),
        "volume_rel_change": worst_dv,
        "area_rel_change": worst_da,
        "max_deviation": worst_dev["max_deviation"],
        "face_groups": [dict(g, solid=k) for k, r in enumerate(reports) for g in r["face_groups"]],
        "time_s": sum(r["time_s"] for r in reports),
        "cpu_s": sum(r["cpu_s"] for r in reports),
        "notes": [f"{len(reports)} solids: face indices are per solid (see 'solids')"],
        "solids": reports,
    }


def _png(before_shape: Any, result: Any, path: Path, title: str) -> None:
    """The before/after picture, written to ``path`` (a staged temporary)."""
    from medax.cad.simplify.tessellate import face_triangles
    from medax.viz.before_after import plot_before_after

    rep = result.report()
    before = face_triangles(before_shape)
    after = face_triangles(result.shape)
    kb, ka = colour_keys(rep, len(before))
    plot_before_after(before, after, kb, ka, path, title)
