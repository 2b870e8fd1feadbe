"""``python -m medax`` is the ``medax`` command."""

import subprocess
import sys

from medax import __version__


def test_python_m_medax_runs_the_command(tmp_path):
    run = subprocess.run(
        [sys.executable, "-m", "medax", "samples", "regions.json", "-d", str(tmp_path)],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "regions.json").is_file()
    version = subprocess.run([sys.executable, "-m", "medax", "--version"], capture_output=True)
    assert version.stdout.decode().strip() == f"medax {__version__}"
