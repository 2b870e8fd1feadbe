"""Fillet simplification: medax against OCCT's BRepAlgoAPI_Defeaturing, same run, same faces.

For each part (the shared STEP parts when present, and a generated part with 500+ faces):
classify, simplify with medax, then remove the blend faces medax removed (all blends when
medax removed none) with ``BRepAlgoAPI_Defeaturing``. Printed per part: faces after,
validity, relative volume change (defeaturing changes the shape; medax must not) and the
time ratio medax / defeaturing.

    .venv/bin/python benchmarks/bench_simplify.py [PART.step ...] [--parts box12,grid8,...]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

SHARED = Path(__file__).resolve().parents[1] / ".." / "shared" / "bench" / "cad"


#: OCCT's defeaturing of hundreds of blends can run for many minutes: it runs in a child
#: process and is stopped after this many seconds (reported as "timeout").
DEFEATURE_TIMEOUT = 180.0

_CHILD = """
import sys, time
from OCP.BRep import BRep_Builder
from OCP.BRepTools import BRepTools
from OCP.TopoDS import TopoDS_Shape
from OCP.BRepAlgoAPI import BRepAlgoAPI_Defeaturing
from OCP.TopAbs import TopAbs_FACE
from medax.cad.simplify.occ import shape_map
shape = TopoDS_Shape()
BRepTools.Read_s(shape, sys.argv[1], BRep_Builder())
fmap = shape_map(shape, TopAbs_FACE)
t0 = time.perf_counter()
d = BRepAlgoAPI_Defeaturing()
d.SetShape(shape)
for i in map(int, sys.argv[3].split(",")):
    d.AddFaceToRemove(fmap.FindKey(i + 1))
d.SetRunParallel(False)
d.Build()
dt = time.perf_counter() - t0
if d.IsDone():
    BRepTools.Write_s(d.Shape(), sys.argv[2])
print(dt)
"""


def defeature(shape: Any, faces: list[int]) -> tuple[Any | None, float | str]:
    """Remove ``faces`` (indices) with ``BRepAlgoAPI_Defeaturing`` in a child process;
    (result or None, seconds or "timeout")."""
    import subprocess
    import tempfile

    from OCP.BRep import BRep_Builder
    from OCP.BRepTools import BRepTools
    from OCP.TopoDS import TopoDS_Shape

    with tempfile.TemporaryDirectory() as tmp:
        src, dst = f"{tmp}/in.brep", f"{tmp}/out.brep"
        BRepTools.Write_s(shape, src)
        arg = ",".join(map(str, faces))
        try:
            out = subprocess.run(
                [sys.executable, "-c", _CHILD, src, dst, arg],
                capture_output=True,
                text=True,
                timeout=DEFEATURE_TIMEOUT,
            )
        except subprocess.TimeoutExpired:
            return None, "timeout"
        try:
            dt: float | str = float(out.stdout.strip().splitlines()[-1])
        except (IndexError, ValueError):
            return None, "failed"
        if not Path(dst).exists():
            return None, dt
        result = TopoDS_Shape()
        BRepTools.Read_s(result, dst, BRep_Builder())
        return result, dt


def bench(label: str, cls: Any) -> None:
    from OCP.TopAbs import TopAbs_FACE

    from medax.cad.simplify import simplify, specs_from_classification
    from medax.cad.simplify.occ import count
    from medax.cad.simplify.validate import check, volume

    specs = specs_from_classification(cls)
    t0 = time.perf_counter()
    r = simplify(cls.shape, specs)
    t_medax = time.perf_counter() - t0
    removed = r.blends_removed or list(specs.blend_faces)
    shape, t_def = defeature(cls.shape, list(removed))
    if shape is None:
        d_faces, d_valid, d_dv = "-", False, float("nan")
    else:
        c = check(shape)
        d_faces, d_valid = count(shape, TopAbs_FACE), c.valid
        d_dv = (c.volume - volume(cls.shape)) / volume(cls.shape)
    print(
        f"{label:34s} faces {r.faces_before:4d} | medax -> {r.faces_after:4d} valid {r.valid!s:5s} "
        f"dV {r.volume_rel_change:+.1e} dev {r.max_deviation / r.diagonal:.1e} "
        f"removed {len(r.blends_removed):3d} kept {len(r.blends_kept):3d} {t_medax:6.2f} s | "
        f"defeaturing -> {d_faces!s:>4s} valid {d_valid!s:5s} dV {d_dv:+.1e} {_secs(t_def)} | "
        f"time ratio medax/defeaturing {_ratio(t_medax, t_def)}"
    )
    kept: dict[str, int] = {}
    for _, reason in r.blends_kept:
        kept[reason] = kept.get(reason, 0) + 1
    for reason, n in sorted(kept.items(), key=lambda kv: -kv[1]):
        print(f"    kept {n} x: {reason}")


def _secs(t: float | str) -> str:
    return f"{t:6.2f} s" if isinstance(t, float) else f"{t:>8s}"


def _ratio(a: float, b: float | str) -> str:
    if isinstance(b, float):
        return f"{a / max(b, 1e-9):.2f}"
    return f"< {a / DEFEATURE_TIMEOUT:.2f} (defeaturing {b} after {DEFEATURE_TIMEOUT:.0f} s)"


#: The generated and catalogue parts, by the name ``--parts`` takes.
GENERATED = ("box12", "rounded_chain", "variable", "slanted", "boss_grid", "grid2", "grid8")


def _generated(name: str) -> tuple[str, Any]:
    """(label, shape) of a generated part."""
    from medax.cad import parts as catalogue
    from medax.cad.simplify import parts

    if name == "box12":
        return "box, 12 edges filleted (8 corners)", parts.box_all_fillets().shape
    if name == "rounded_chain":
        return "rounded box + top chain (tori on fillets)", catalogue.rounded_box_chain().shape
    if name == "variable":
        return "box, variable-radius fillet (B-spline)", catalogue.variable_radius_box().shape
    if name == "slanted":
        return "plate, slanted boss (B-spline blend: ring faces)", catalogue.slanted_boss().shape
    if name == "boss_grid":
        return "plate, 8x8 bosses, top + root fillets", catalogue.boss_grid(8).shape
    n = int(name[4:])
    part = parts.grid_plate(n, n)
    return f"grid plate {n}x{n} ({len(part.blends)} fillets)", part.shape


def main(argv: list[str]) -> int:
    import argparse

    from medax.cad.classify import classify_file, classify_solid
    from medax.cad.reader import heal

    ap = argparse.ArgumentParser(
        description="medax simplify against BRepAlgoAPI_Defeaturing removing the same faces, "
        "in the same run: faces after, validity, volume change, deviation, time ratio."
    )
    ap.add_argument("files", nargs="*", help="STEP parts (default: ../shared/bench/cad/*.st*p)")
    ap.add_argument(
        "--parts",
        default=",".join(GENERATED),
        help=f"generated parts to run, comma-separated from {','.join(GENERATED)} "
        "('' for none; grid8 has 586 faces: the 500-face target)",
    )
    args = ap.parse_args(argv)
    files = [Path(a) for a in args.files] or sorted(SHARED.glob("*.st*p"))
    for f in files:
        for k, cls in enumerate(classify_file(str(f))):
            bench(f"{f.name}[{k}]", cls)
    for name in filter(None, args.parts.split(",")):
        if name not in GENERATED:
            ap.error(f"unknown part {name!r} (expected one of {', '.join(GENERATED)})")
        label, shape = _generated(name)
        bench(label, classify_solid(heal(shape)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
