"""The numba options of the compiled kernels (``*_kernel.py``, :mod:`medax.geometry.kernels`).

``KERNEL`` for the kernels called from Python: cached (only the first run after an install
compiles), numpy's floating-point error model (no division checks), and no C callback
wrapper (never used). ``HELPER`` for the functions called only from compiled code: no
CPython wrapper either (generating and compiling the unboxing of their arguments was a
tenth of the first run's compile time).
"""

from typing import Any

KERNEL: dict[str, Any] = {"cache": True, "error_model": "numpy", "no_cfunc_wrapper": True}
HELPER: dict[str, Any] = {**KERNEL, "no_cpython_wrapper": True}
