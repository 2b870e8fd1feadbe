"""Batch runs: classify, simplify and mesh many parts on a Dask cluster (``medax batch``).

Every part runs in a child process of a Dask worker (:mod:`medax.batch.part`), so an OCCT
crash or hang costs one part; the client (:mod:`medax.batch.run`) sends paths and options,
gets back one JSON record per part and appends it to ``OUTDIR/records.jsonl``
(:mod:`medax.batch.records`), which also makes a run resumable. This package never imports
OCP: the work itself is the ``medax`` subcommands, run in-process in the child.
"""

from __future__ import annotations

from medax.batch.run import BatchOptions, BatchResult, run_batch

__all__ = ["BatchOptions", "BatchResult", "run_batch"]
