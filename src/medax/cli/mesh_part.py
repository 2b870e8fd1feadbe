"""``medax mesh PART.step``: one conforming quad surface mesh of a CAD part, with groups.

Everything is validated before any work; the mesh, report and plot are written only once
the whole part is meshed and checked (:func:`medax.cad.part_mesh.mesh_part`).
"""

from __future__ import annotations

import argparse
import logging
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from medax.cli.limits import check_estimate, part_estimate
from medax.errors import InputError
from medax.schemas import stamp

log = logging.getLogger(__name__)

PLOT_SUFFIXES = (".png", ".svg", ".pdf")
#: units of the report besides length (angles in degrees, times in seconds)
UNITS = {"angle": "deg", "time": "s"}


def parse_faces(text: str) -> list[int] | None:
    """``"all"`` -> None, ``"1,4,7"`` -> [1, 4, 7]; InputError otherwise."""
    if text.strip().lower() == "all":
        return None
    try:
        out = [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise InputError(f"--faces must be 'all' or face indices I,J,K, got '{text}'") from None
    if not out or min(out) < 0:
        raise InputError(f"--faces must be 'all' or face indices >= 0, got '{text}'")
    return out


def run_part(args: argparse.Namespace) -> int:
    from medax.cad.part_mesh import mesh_part
    from medax.cad.part_report import part_report
    from medax.cli.outputs import JSON_SUFFIXES, Output, check_outputs
    from medax.io_utils import staged_outputs, write_json
    from medax.mesh.export import format_from_path
    from medax.mesh.grouped_export import MeshGroups, write_grouped_mesh
    from medax.mesh.quality import quad_quality

    fmt = format_from_path(args.output, args.format)
    if args.size is None:
        raise InputError("a CAD part needs --size (target edge length, model units)")
    if not (math.isfinite(args.size) and args.size > 0.0):
        raise InputError(f"--size must be positive, got {args.size}")
    for opt in ("divisions", "region", "boundary", "tol"):
        if getattr(args, opt) is not None:
            raise InputError(f"--{opt} applies to regions, not to CAD parts")
    if args.method != "ratio":
        raise InputError("--method applies to regions, not to CAD parts")
    faces = parse_faces(args.faces)
    if args.plot and Path(args.plot).suffix.lower() not in PLOT_SUFFIXES:
        raise InputError(f"--plot {args.plot}: use a {', '.join(PLOT_SUFFIXES)} file name")
    check_outputs(
        [
            Output("-o", args.output, None),
            Output("--report", args.report, JSON_SUFFIXES),
            Output("--plot", args.plot, PLOT_SUFFIXES),
        ],
        {"part": args.regions},
    )

    def progress(msg: str) -> None:
        log.info("mesh: %s", msg)

    def check_size(shapes: list[Any]) -> None:
        from medax.cad.part_mesh import surface_area

        est = part_estimate(sum(surface_area(sh) for sh in shapes), args.size)
        check_estimate(est, f"--size {args.size:g}", args.force)

    t0 = time.perf_counter()
    solids, unit = _solids(args.regions, args.simplify, progress, check_size)
    if len(solids) > 1 and faces is not None:
        raise InputError(f"{args.regions}: {len(solids)} solids; --faces needs a single solid")
    meshes = []
    for k, shape in enumerate(solids):
        if len(solids) > 1:
            progress(f"solid {k + 1}/{len(solids)}")
        meshes.append(mesh_part(shape, args.size, faces, not args.all_gmsh, progress))
    points, quads, qgroup, qnames, lines, lgroup, lnames = _combine(meshes)
    groups = MeshGroups(qgroup, qnames, lines, lgroup, lnames)
    quality = quad_quality(points, quads)
    reports = [part_report(m, str(args.regions), args.size) for m in meshes]
    rep: dict[str, Any] = reports[0] if len(reports) == 1 else {"solids": reports}
    total = time.perf_counter() - t0
    sj = quality.scaled_jacobian
    n_struct = sum(len(m.structured_faces) for m in meshes)
    n_faces = sum(len(m.faces) for m in meshes)
    print(
        f"{args.regions}: {len(quads)} quads, {len(points)} nodes, {n_struct}/{n_faces} faces "
        f"structured, {total:.2f} s; scaled Jacobian min {sj.min():.3f} "
        f"p5 {np.percentile(sj, 5):.3f}"
    )
    with staged_outputs() as out:  # all outputs or none
        target = out.path(args.output, "-o")
        write_grouped_mesh(target, points, quads, groups, quality.as_dict(), fmt)
        if args.report:
            rep["total_time_s"] = total
            rep = stamp("part-mesh-report", rep, unit, _tolerances(args.simplify), **UNITS)
            write_json(out.path(args.report, "--report"), rep, "--report")
        if args.plot:
            from medax.viz.part_plot import plot_part_mesh

            title = (
                f"{Path(args.regions).name}: {len(quads)} quads, {n_struct}/{n_faces} faces medial"
            )
            plot_part_mesh(points, quads, sj, out.path(args.plot, "--plot"), title)
    for path in (args.output, args.report, args.plot):
        if path:
            print(f"wrote {path}")
    return 0


def _tolerances(simplify: bool) -> dict[str, float]:
    """The tolerances of a part mesh (and of the simplification before it)."""
    from medax.cad import part_mesh

    tols = {
        "boundary_match_rel": part_mesh.BOUNDARY_MATCH,
        "match_tol_rel": part_mesh.MATCH_TOL,
    }
    if simplify:
        from medax.cli.simplify import simplify_tolerances

        tols |= simplify_tolerances()
    return tols


def _solids(
    path: str, simplify: bool, progress: Any, check: Callable[[list[Any]], None]
) -> tuple[list[Any], str]:
    """The file's solids, simplified first if asked, and their length unit; ``check`` is
    called on the solids as read, before any simplification."""
    from medax.cad.reader import read_part

    part = read_part(path)
    check(list(part.solids))
    if not simplify:
        return list(part.solids), part.unit
    from medax.cad.classify import classify_solid
    from medax.cad.simplify import simplify as run_simplify
    from medax.cad.simplify import specs_from_classification

    out = []
    classes = [  # (the solids as read above: the file is not read twice)
        classify_solid(s, source=part.source, unit=part.unit, index=k)
        for k, s in enumerate(part.solids)
    ]
    for k, cls in enumerate(classes):
        specs = specs_from_classification(cls)
        progress(f"solid {k}: {len(cls.faces)} faces, simplifying")
        r = run_simplify(cls.shape, specs, progress=progress)
        progress(f"solid {k}: faces {r.faces_before} -> {r.faces_after}")
        out.append(r.shape)
    return out, classes[0].unit


def _combine(meshes: list[Any]) -> tuple[Any, ...]:
    """One node table and group set from several solids' meshes (names prefixed by the
    solid's number when there are several)."""
    pts, quads, qg, lines, lg = [], [], [], [], []
    qnames: dict[int, str] = {}
    lnames: dict[int, str] = {}
    offset = face_off = edge_off = 0
    for k, m in enumerate(meshes):
        pre = f"s{k}_" if len(meshes) > 1 else ""
        pts.append(m.points)
        quads.append(m.quads + offset)
        lines.append(m.lines + offset)
        qg.append(m.quad_face + face_off)
        lg.append(m.line_edge + edge_off)
        for f in np.unique(m.quad_face).tolist():
            qnames[f + face_off] = f"{pre}face_{f}"
        for e in np.unique(m.line_edge).tolist():
            lnames[e + edge_off] = f"{pre}edge_{e}"
        offset += len(m.points)
        face_off += int(m.quad_face.max(initial=-1)) + 1
        edge_off += len(m.edge_counts)
    return (
        np.concatenate(pts),
        np.concatenate(quads),
        np.concatenate(qg),
        qnames,
        np.concatenate(lines),
        np.concatenate(lg),
        lnames,
    )
