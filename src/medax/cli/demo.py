"""``medax demo``: run every capability on the embedded samples into ``./medax-demo/``.

Each capability contributes a ``medax.cli.demo_<part>`` module with
``demo(outdir: Path) -> list[Path]`` returning the files it wrote.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import time
from pathlib import Path

log = logging.getLogger(__name__)

DEMO_PARTS = ("demo_axis", "demo_mesh", "demo_cad", "demo_simplify", "demo_part_mesh")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help="run medax on the embedded samples",
        description="Trace medial axes, mesh and simplify the embedded samples; write plots, "
        "JSON, meshes and STEP files to OUTDIR and list them.",
    )
    p.add_argument("-o", "--outdir", default="medax-demo", help="output folder (medax-demo)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    outdir = Path(args.outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    for name in DEMO_PARTS:
        try:
            module = importlib.import_module(f"medax.cli.{name}")
        except ModuleNotFoundError as err:
            if err.name == f"medax.cli.{name}":
                continue
            raise
        t0 = time.perf_counter()
        written = module.demo(outdir)
        dt = time.perf_counter() - t0
        log.info("demo: [%s] %.1f s", name.removeprefix("demo_"), dt)
        for path in written:
            print(f"wrote {path}")
    return 0
