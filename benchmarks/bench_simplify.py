"""Fillet simplification: medax against OCCT's BRepAlgoAPI_Defeaturing, same run, same faces.

For each part (the shared STEP parts when present, and a generated part with 500+ faces):
classify, simplify with medax, then remove the blend faces medax removed (all blends when
medax removed none) with ``BRepAlgoAPI_Defeaturing``. Printed per part: faces after,
validity, relative volume change (defeaturing changes the shape; medax must not) and the
time ratio medax / defeaturing.

    .venv/bin/python benchmarks/bench_simplify.py [PART.step ...]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

SHARED = Path(__file__).resolve().parents[1] / ".." / "shared" / "bench" / "cad"


def defeature(shape: Any, faces: list[Any]) -> tuple[Any | None, float]:
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Defeaturing

    t0 = time.perf_counter()
    d = BRepAlgoAPI_Defeaturing()
    d.SetShape(shape)
    for f in faces:
        d.AddFaceToRemove(f)
    d.SetRunParallel(False)
    d.Build()
    dt = time.perf_counter() - t0
    return (d.Shape() if d.IsDone() else None), dt


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
    shape, t_def = defeature(cls.shape, [cls.face(i) for i in removed])
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
        f"defeaturing -> {d_faces!s:>4s} valid {d_valid!s:5s} dV {d_dv:+.1e} {t_def:6.2f} s | "
        f"time ratio medax/defeaturing {t_medax / max(t_def, 1e-9):.2f}"
    )
    kept: dict[str, int] = {}
    for _, reason in r.blends_kept:
        kept[reason] = kept.get(reason, 0) + 1
    for reason, n in sorted(kept.items(), key=lambda kv: -kv[1]):
        print(f"    kept {n} x: {reason}")


def main(argv: list[str]) -> int:
    from medax.cad.classify import classify_file, classify_solid
    from medax.cad.reader import heal
    from medax.cad.simplify import parts

    files = [Path(a) for a in argv] or sorted(SHARED.glob("*.st*p"))
    for f in files:
        for k, cls in enumerate(classify_file(str(f))):
            bench(f"{f.name}[{k}]", cls)
    part = parts.grid_plate(8, 8)
    bench(f"generated grid plate ({len(part.blends)} fillets)", classify_solid(heal(part.shape)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
