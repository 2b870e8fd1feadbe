"""``python -m medax.batch.child FD``: one part in a new interpreter, for Dask workers
that are daemonic processes (see :func:`medax.batch.part.child_main`)."""

from __future__ import annotations

import sys

from medax.batch.part import child_main

if __name__ == "__main__":
    sys.exit(child_main())
