"""``medax samples``: list the packaged sample files, or copy them into a folder."""

from __future__ import annotations

import argparse


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "samples",
        help="list the packaged sample files or copy them into a folder",
        description="Without NAME: list the sample files shipped with medax (regions and STEP "
        "parts). With NAMEs or --all: copy them into --dir (created if missing). An existing "
        "file is never overwritten: if any target exists, nothing is copied.",
        epilog="example: medax samples --all -d samples",
    )
    p.add_argument("names", nargs="*", metavar="NAME", help="sample file(s) to copy")
    p.add_argument("--all", action="store_true", help="copy every sample")
    p.add_argument("-d", "--dir", default=".", help="folder to copy into (default: .)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from medax.errors import InputError
    from medax.samples import SAMPLES, copy_samples, sample_path

    if args.all and args.names:
        raise InputError("give sample names or --all, not both")
    if not (args.all or args.names):
        width = max(len(n) for n in SAMPLES)
        for name, what in SAMPLES.items():
            size = sample_path(name).stat().st_size
            print(f"{name:<{width}}  {size / 1024:5.0f} KB  {what}")
        print("copy with: medax samples NAME... -d FOLDER (or --all)")
        return 0
    for path in copy_samples(list(SAMPLES) if args.all else args.names, args.dir):
        print(f"wrote {path}")
    return 0
