"""Start-up cost of the compiled kernels: the first-run compile and the cached warm start.

* cold: a fresh process with an empty ``NUMBA_CACHE_DIR`` (a new temporary directory) imports
  :mod:`medax.geometry.kernels` and runs ``kernels.warm_up()``; reported are its CPU time in
  all (import included) and per kernel (the CPU time of each of ``warm_up``'s calls; a
  helper compiled inside its first caller counts to that caller), the best of ``--repeat``
  runs (the minimum per entry);
* warm: ``medax axis`` on a shared region (``wavy``, both pairs) with the cache populated
  by the cold runs, the child's CPU time (user + system), the best of ``--warm`` runs.

    python benchmarks/bench_compile.py [--repeat 3] [--warm 5] [--region wavy]

Target (issue 22): the cold compile at most 10 s CPU; the warm start at most 0.2 s over
the numpy-only code.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

#: the child of a cold run: times each call of ``warm_up`` by wrapping the kernels it calls
_COLD = r"""
import json, time
t0 = time.process_time()
from medax.geometry import kernels
t_import = time.process_time() - t0
times = {}
def wrap(name, f):
    def timed(*a, **k):
        s = time.process_time()
        r = f(*a, **k)
        times[name] = times.get(name, 0.0) + time.process_time() - s
        return r
    return timed
# (not the kernels other compiled code calls: numba resolves those globals at compile time)
used = {
    n for f in vars(kernels).values() if hasattr(f, "py_func") for n in f.py_func.__code__.co_names
}
for name in list(vars(kernels)):
    obj = getattr(kernels, name)
    if any(obj is k for k in kernels._COMPILED) and name not in used:
        setattr(kernels, name, wrap(name, obj))
kernels.warm_up()
total = time.process_time() - t0
times["(other: called by compiled code)"] = total - t_import - sum(times.values())
sigs = {k.py_func.__module__ + "." + k.__name__: len(k.signatures) for k in kernels._COMPILED}
print(json.dumps({"total": total, "import": t_import, "kernels": times, "signatures": sigs}))
"""


def _env(cache: str) -> dict[str, str]:
    env = dict(os.environ)
    env["NUMBA_CACHE_DIR"] = cache
    src = str(Path(__file__).resolve().parents[1] / "src")
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    return env


def cold(cache: str) -> dict:  # type: ignore[type-arg]
    """One cold run of ``warm_up`` into the (empty) cache directory ``cache``."""
    out = subprocess.run(
        [sys.executable, "-c", _COLD], env=_env(cache), capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def warm(cache: str, regions: str, region: str) -> float:
    """CPU time (s, user + system) of one ``medax axis`` run with the cache ``cache``."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "medax", "axis", regions, "--region", region]
        cmd += ["--pair", "both", "-q", "-o", str(Path(tmp) / "axis.json")]
        proc = subprocess.Popen(cmd, env=_env(cache), stdout=subprocess.DEVNULL)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode:
            raise SystemExit(f"medax axis failed ({proc.returncode})")
        return usage.ru_utime + usage.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3, help="cold runs (best of)")
    ap.add_argument("--warm", type=int, default=5, help="warm runs (best of)")
    ap.add_argument("--region", default="wavy")
    ap.add_argument("--regions", default=None, help="regions JSON (default: the shipped one)")
    args = ap.parse_args()
    regions = args.regions or str(
        Path(__file__).resolve().parents[1] / "src" / "medax" / "data" / "regions.json"
    )
    best: dict | None = None  # type: ignore[type-arg]
    with tempfile.TemporaryDirectory() as keep:
        for r in range(args.repeat):
            with tempfile.TemporaryDirectory() as cache:
                res = cold(cache)
            print(f"cold run {r + 1}: {res['total']:.2f} s CPU (import {res['import']:.2f} s)")
            if best is None:
                best = res
            else:
                best["total"] = min(best["total"], res["total"])
                best["import"] = min(best["import"], res["import"])
                for k, v in res["kernels"].items():
                    best["kernels"][k] = min(best["kernels"].get(k, v), v)
        assert best is not None
        print(f"cold compile, best of {args.repeat}: {best['total']:.2f} s CPU in all")
        print(f"  import (numba and medax): {best['import']:.2f} s")
        for k, v in sorted(best["kernels"].items(), key=lambda kv: -kv[1]):
            print(f"  {k:<20s} {v:6.2f} s")
        multi = {k: n for k, n in best["signatures"].items() if n != 1}
        print(f"  signatures after warm_up: {multi or 'one per kernel'}")
        if args.warm:
            cold(keep)  # populate the cache
            times = [warm(keep, regions, args.region) for _ in range(args.warm)]
            print(
                f"warm start (medax axis {args.region}, both pairs), best of {args.warm}: "
                f"{min(times):.3f} s CPU (all: {', '.join(f'{t:.3f}' for t in times)})"
            )


if __name__ == "__main__":
    main()
