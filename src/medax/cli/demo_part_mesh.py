"""Demo part: quad meshes of CAD parts, through the command line.

The box with all 12 edges filleted (built with OCCT, 26 faces) is meshed after ``--simplify``
(6 four-sided faces, all medial grids), and the L-bracket as it is (9 of 11 faces medial,
the hole's cylinder too, 4-sided with its seam; gmsh's quads on the two faces with the
hole): the mesh with its groups, the report and the picture coloured by scaled Jacobian.
"""

from __future__ import annotations

from pathlib import Path

from medax.cli.main import main


def demo(outdir: Path) -> list[Path]:
    """Write ``part-mesh-<part>{-input.step,.msh,.json,.png}`` into ``outdir``."""
    from medax.cad import parts as catalogue
    from medax.cad.simplify import parts
    from medax.cad.simplify.step_out import write_step

    written: list[Path] = []
    for name, shape, extra in (
        ("box-12-edges", parts.box_all_fillets().shape, ["--simplify"]),
        ("l-bracket", catalogue.l_bracket().shape, []),
    ):
        src = write_step(shape, outdir / f"part-mesh-{name}-input.step")
        out, rep, png = (outdir / f"part-mesh-{name}{ext}" for ext in (".msh", ".json", ".png"))
        args = ["mesh", str(src), "--size", "2", "-o", str(out), "--report", str(rep)]
        if main([*args, "--plot", str(png), *extra]) != 0:
            raise RuntimeError(f"demo mesh of {name} failed")
        written += [src, out, rep, png]
    return written
