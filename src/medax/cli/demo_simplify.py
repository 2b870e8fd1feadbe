"""Demo part: fillet simplification of two filleted parts built with OCCT at run time.

A box with four filleted vertical edges (10 -> 6 faces, extrusion surfaces), a plate with a
filleted boss and a hole (10 -> 9 faces, revolution surfaces) and a boss filleted at its root
and top (10 -> 8 faces; the top face holds the pole of its revolution surface) and a box with
all 12 edges filleted (26 -> 6 faces: eight sphere corners split, fitted faces) and a box
with rounded vertical edges whose top loop was filleted after them (18 -> 6 faces: the tori
ride on the vertical fillets and are split by bridges) and a plate with a slanted boss
whose root blend is a B-spline rolling ball (11 -> 10 faces: the ring route's periodic
fitted faces): the input STEP, the simplified STEP (faces coloured by merged group), the JSON
report, the before/after picture and the interactive 3D view (HTML) of each.
"""

from __future__ import annotations

from pathlib import Path

from medax.cli.main import main


def demo(outdir: Path) -> list[Path]:
    """Write ``simplify-<part>{-input.step,.step,.json,.png,.html}`` into ``outdir``."""
    from medax.cad import parts as catalogue
    from medax.cad.simplify import parts
    from medax.cad.simplify.step_out import write_step

    written: list[Path] = []
    for name, part in (
        ("box", parts.box_vertical_fillets()),
        ("boss", parts.plate_with_boss()),
        ("boss-top", parts.boss_top_fillet(2.0, root=True)),
        ("box-12-edges", parts.box_all_fillets()),
        ("rounded-box-chain", catalogue.rounded_box_chain()),
        ("slanted-boss", catalogue.slanted_boss()),
    ):
        src = write_step(part.shape, outdir / f"simplify-{name}-input.step")
        out, rep, png, view = (
            outdir / f"simplify-{name}{ext}" for ext in (".step", ".json", ".png", ".html")
        )
        argv = ["simplify", str(src), "-o", str(out), "--report", str(rep), "--png", str(png)]
        if main([*argv, "--view3d", str(view)]) != 0:
            raise RuntimeError(f"demo simplify of {name} failed")
        written += [src, out, rep, png, view]
    return written
