"""The README works as pasted: every ``sh``/``bash`` block runs from a fresh folder and
writes the files it names, the Python blocks run, and the file stays short.

``.venv/bin/X`` is resolved to the running interpreter's environment (``make test`` runs in
``.venv``); ``text`` blocks (``make``, ``pip install``, printed output) are not run.
"""

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
#: options whose next argument is a file the command writes
FILE_OPTIONS = ("-o", "--output", "--report", "--plot", "--png")
FOLDER_OPTIONS = ("-d", "--dir")


def blocks(*langs: str) -> list[str]:
    """The bodies of the README's fenced blocks in ``langs``."""
    text = README.read_text(encoding="utf-8")
    found = re.findall(r"^```(\w*)\n(.*?)^```", text, flags=re.M | re.S)
    return [body for lang, body in found if lang in langs]


def commands(block: str) -> list[list[str]]:
    """The block's commands as argument lists (comments, blank lines and ``\\`` handled)."""
    text = block.replace("\\\n", " ")
    lines = (line.split(" #")[0].strip() for line in text.splitlines())
    return [shlex.split(line) for line in lines if line and not line.startswith("#")]


def resolve(argv: list[str]) -> list[str]:
    """``.venv/bin/X`` -> X beside the running interpreter (``python -m medax`` if absent)."""
    head = argv[0]
    if not head.startswith(".venv/bin/"):
        return argv
    name = head.removeprefix(".venv/bin/")
    if name in ("python", "python3"):
        return [sys.executable, *argv[1:]]
    exe = Path(sys.executable).parent / name
    if exe.exists():
        return [str(exe), *argv[1:]]
    assert name == "medax", f"README runs {head}, not found beside {sys.executable}"
    return [sys.executable, "-m", "medax", *argv[1:]]


def written(argv: list[str]) -> tuple[list[str], list[str]]:
    """Files and folders a command is asked to write."""
    files = [b for a, b in zip(argv, argv[1:], strict=False) if a in FILE_OPTIONS]
    folders = [b for a, b in zip(argv, argv[1:], strict=False) if a in FOLDER_OPTIONS]
    return files, folders


def test_readme_is_short():
    assert len(README.read_text(encoding="utf-8").splitlines()) < 200


def test_readme_has_commands_to_run():
    runs = [c for b in blocks("sh", "bash") for c in commands(b)]
    assert runs and all(c[0].startswith(".venv/bin/") for c in runs)
    assert any(c[1:2] == ["samples"] for c in runs)


@pytest.mark.slow
def test_readme_commands_run_from_a_fresh_folder(tmp_path):
    for block in blocks("sh", "bash"):
        for argv in commands(block):
            run = subprocess.run(resolve(argv), cwd=tmp_path, capture_output=True, text=True)
            assert run.returncode == 0, f"{shlex.join(argv)}\n{run.stdout}\n{run.stderr}"
            files, folders = written(argv)
            for name in files:
                path = tmp_path / name
                assert path.is_file() and path.stat().st_size > 0, f"{shlex.join(argv)}: {name}"
            for name in folders:
                assert any((tmp_path / name).iterdir()), f"{shlex.join(argv)}: {name} empty"


@pytest.mark.slow
def test_readme_python_blocks_run(tmp_path):
    """The Python snippets, in order, as one script (later ones use earlier names)."""
    script = "\n".join(blocks("python"))
    run = subprocess.run(
        [sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True
    )
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "simple.step").stat().st_size > 0
