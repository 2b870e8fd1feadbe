"""``medax simplify`` interrupted (SIGINT, SIGTERM) or killed (SIGKILL) mid-work, as a real
process: no partial output, every pre-existing output byte-identical, no temporary left."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

import medax
from medax.cad.simplify import parts as P
from medax.cad.simplify.step_out import write_step

SRC = Path(medax.__file__).resolve().parents[1]
OLD_STEP = b"ISO-10303-21;\n/* the user's previous output */\nEND-ISO-10303-21;\n"
OLD_REPORT = b'{"previous": true}\n'


@pytest.fixture(scope="module")
def part(tmp_path_factory):
    """A box with all 12 edges filleted: ~5 s of work after the first progress line."""
    return write_step(P.box_all_fillets().shape, tmp_path_factory.mktemp("part") / "all12.step")


def _start(part: Path, out: Path, rep: Path) -> subprocess.Popen[str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(SRC), env.get("PYTHONPATH")) if p)
    argv = [sys.executable, "-m", "medax.cli.main", "simplify", str(part), "-o", str(out)]
    return subprocess.Popen(
        [*argv, "--report", str(rep)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        # a shell starting a background job (CI under `cmd &`, nohup) hands it SIGINT
        # ignored, and Python keeps it so: the child is given the default, as at a terminal
        preexec_fn=_default_sigint,
    )


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("sig", "after", "code"),
    [
        (signal.SIGINT, "fillets with a medial curve", 130),
        (signal.SIGINT, "validating", 130),
        (signal.SIGTERM, "splitting", 143),
        (signal.SIGKILL, "validating", -signal.SIGKILL),
    ],
)
def test_interrupted_simplify_leaves_outputs_intact(part, tmp_path, sig, after, code):
    out, rep = tmp_path / "out.step", tmp_path / "report.json"
    out.write_bytes(OLD_STEP)
    rep.write_bytes(OLD_REPORT)
    proc = _start(part, out, rep)
    seen = []
    assert proc.stderr is not None
    for line in proc.stderr:
        seen.append(line)
        if after in line:
            break
    assert proc.poll() is None, f"finished before the signal: {seen}"
    proc.send_signal(sig)
    _, rest = proc.communicate(timeout=120)
    assert proc.returncode == code, rest
    if sig != signal.SIGKILL:
        last = rest.strip().splitlines()[-1]
        assert last.endswith("no output written") and "Traceback" not in rest, rest
    assert out.read_bytes() == OLD_STEP
    assert rep.read_bytes() == OLD_REPORT
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.step", "report.json"]


@pytest.mark.slow
def test_uninterrupted_run_replaces_the_outputs(part, tmp_path):
    """The same command left alone replaces both outputs (so the test above can fail)."""
    out, rep = tmp_path / "out.step", tmp_path / "report.json"
    out.write_bytes(OLD_STEP)
    rep.write_bytes(OLD_REPORT)
    proc = _start(part, out, rep)
    proc.communicate(timeout=300)
    assert proc.returncode == 0
    assert out.read_bytes() != OLD_STEP and b"END-ISO-10303-21;" in out.read_bytes()
    assert b'"faces_after": 6' in rep.read_bytes()
