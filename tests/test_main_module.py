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
    assert version.returncode == 0
    line = version.stdout.decode().strip()
    import numpy
    import OCP

    assert line.startswith(f"medax {__version__}, OpenCASCADE ")
    assert f"(OCP {OCP.__version__})" in line and f"numpy {numpy.__version__}" in line
