"""Face areas on B-spline surfaces: medax's rule against OCCT's adaptive integrator, same run.

For every face of the given parts that lies on a polynomial B-spline surface (the fitted
merged faces of a simplified part: run ``medax simplify`` first and pass its output), the
area by ``medax.cad.face_area.bspline_face_area`` (Green's theorem over the pcurves, the
inner integral split at the knots) and by ``BRepGProp.SurfaceProperties_s`` with a relative
accuracy of 1e-9 (what simplify's validation asked of it). Printed per part: faces
measured, the largest relative difference over the faces whose pcurves meet end to end
and over those with gaps between them (a loose face's pcurves can miss each other at a
vertex: medax closes the gap with a straight piece, OCCT integrates along the pcurves as
they are, and its reading then depends on its direction of integration), and the CPU
times of both with their ratio; per face with ``--faces``.

    .venv/bin/python benchmarks/bench_face_area.py PART.step [...] [--faces]
"""

from __future__ import annotations

import sys
import time
from typing import Any

#: A face's pcurves "meet" when they miss each other by at most this (parameter units).
GAP = 1e-9


def _occt_area(face: Any, eps: float) -> float:
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props, eps, False)
    return float(props.Mass())


def measure(path: str, per_face: bool) -> tuple[int, float, int, float, float, float]:
    """(faces, largest relative difference on faces whose pcurves meet, faces with gaps,
    largest difference on those, medax CPU s, OCCT CPU s) for one part."""
    from OCP.BRep import BRep_Tool

    from medax.cad.face_area import bspline_face_area, pcurve_gap
    from medax.cad.reader import read_part
    from medax.cad.simplify.occ import faces_of

    part = read_part(path)
    n, worst, n_gap, worst_gap, t_ours, t_occt = 0, 0.0, 0, 0.0, 0.0, 0.0
    for solid in part.solids:
        for face in faces_of(solid):
            t = time.process_time()
            ours = bspline_face_area(face)
            dt = time.process_time() - t
            if ours is None:
                continue
            t = time.process_time()
            ref = _occt_area(face, 1e-9)
            dt_occt = time.process_time() - t
            rel = abs(ours - ref) / ref
            gap = pcurve_gap(face)
            n += 1
            if gap > GAP:
                n_gap, worst_gap = n_gap + 1, max(worst_gap, rel)
            else:
                worst = max(worst, rel)
            t_ours, t_occt = t_ours + dt, t_occt + dt_occt
            if per_face:
                s = BRep_Tool.Surface_s(face)
                print(
                    f"  {s.NbUPoles()} x {s.NbVPoles()} poles: {ours:.9g} / {ref:.9g} "
                    f"({rel:.1e}, pcurve gap {gap:.1e}), {dt:.3f} s / {dt_occt:.3f} s"
                )
    return n, worst, n_gap, worst_gap, t_ours, t_occt


def main(argv: list[str]) -> int:
    per_face = "--faces" in argv
    paths = [a for a in argv if not a.startswith("--")]
    if not paths:
        print(__doc__)
        return 2
    print(
        "| part | B-spline faces | largest difference | with pcurve gaps: faces, "
        "largest difference | medax s | OCCT s | ratio |"
    )
    print("|---|---|---|---|---|---|---|")
    for path in paths:
        n, worst, n_gap, worst_gap, a, b = measure(path, per_face)
        ratio = f"{a / b:.2f}x" if b > 0 else "-"
        name = path.rsplit("/", 1)[-1]
        print(
            f"| {name} | {n} | {worst:.1e} | {n_gap}, {worst_gap:.1e} | {a:.2f} | {b:.2f} "
            f"| {ratio} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
