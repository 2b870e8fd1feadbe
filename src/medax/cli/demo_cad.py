"""Demo part: a filleted part built with OCCT at run time, classified, axes traced, drawn."""

from __future__ import annotations

from pathlib import Path


def demo(outdir: Path) -> list[Path]:
    """Build a filleted box and a plate with a filleted boss, write each as STEP, classify
    it like ``medax classify`` does, and write ``classes-<part>.json`` and
    ``classes-<part>.png`` into ``outdir``."""
    from medax.cad import parts
    from medax.cad.simplify.step_out import write_step
    from medax.cli.classify import classify_part, render_solids
    from medax.io_utils import write_json

    written: list[Path] = []
    for name, built in (("box", parts.box_random(0)), ("boss", parts.plate_with_boss())):
        step = write_step(built.shape, outdir / f"filleted-{name}.step")
        written.append(step)
        report, solids = classify_part(step)
        written.append(write_json(outdir / f"classes-{name}.json", report))
        written.append(render_solids(solids, outdir / f"classes-{name}.png", title=step.name))
    return written
