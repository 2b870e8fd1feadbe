"""``-q`` / ``-v`` on every subcommand, before and after its name; stage messages and progress
go through :mod:`logging`, the result stays on stdout."""

from __future__ import annotations

import argparse
import logging

import pytest

from medax._progress import log_progress
from medax.cli.main import build_parser, main
from medax.samples import copy_samples

#: enough arguments for each subcommand to parse (parsing only: nothing runs)
MINIMAL = {
    "axis": ["r.json", "--region", "wavy"],
    "mesh": ["r.json", "-o", "m.vtu"],
    "classify": ["p.step"],
    "simplify": ["p.step", "-o", "s.step"],
    "samples": [],
    "demo": [],
}


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_every_subcommand_has_q_and_v():
    subs = _subparsers()
    assert set(MINIMAL) <= set(subs)
    for name, p in subs.items():
        opts = set(p._option_string_actions)
        assert {"-q", "--quiet", "-v", "--verbose"} <= opts, name


@pytest.mark.parametrize("name", sorted(MINIMAL))
@pytest.mark.parametrize(
    "where, verbose, quiet",
    [("before", "-v", None), ("after", "-v", None), ("before", None, "-q"), ("after", None, "-q")],
)
def test_flags_before_and_after_the_subcommand(name, where, verbose, quiet):
    flag = verbose or quiet
    argv = [flag, name, *MINIMAL[name]] if where == "before" else [name, *MINIMAL[name], flag]
    args = build_parser().parse_args(argv)
    assert args.verbose_before + args.verbose == (1 if verbose else 0)
    assert args.quiet_before + args.quiet == (1 if quiet else 0)


def test_flags_on_both_sides_add_up():
    args = build_parser().parse_args(["-v", "samples", "-v"])
    assert args.verbose_before + args.verbose == 2


@pytest.fixture(scope="module")
def samples(tmp_path_factory):
    folder = tmp_path_factory.mktemp("samples")
    copy_samples(["regions.json", "filleted-boss.step"], folder)
    return folder


def _mesh(samples, tmp_path, *flags):
    return main(
        ["mesh", str(samples / "regions.json"), "--region", "wavy", "--divisions", "6,6",
         "-o", str(tmp_path / "m.vtu"), *flags]
    )  # fmt: skip


def test_default_shows_stage_messages_and_q_silences_them(samples, tmp_path, capsys):
    assert _mesh(samples, tmp_path) == 0
    out, err = capsys.readouterr()
    assert "medax mesh: region 'wavy', 6x6 quads" in err
    assert "6x6 quads (ratio)" in out and "wrote" in out  # the result: stdout
    assert _mesh(samples, tmp_path, "-q") == 0
    out, err = capsys.readouterr()
    assert err == "" and "6x6 quads (ratio)" in out


def test_verbose_shows_progress_with_counts(samples, capsys):
    pytest.importorskip("OCP")
    part = str(samples / "filleted-boss.step")
    assert main(["classify", part, "--no-axes"]) == 0
    err = capsys.readouterr().err
    assert "medax classify: solid 0: 11 faces, 2 fillets" in err
    assert "faces examined for fillets" not in err
    assert main(["-v", "classify", part, "--no-axes"]) == 0
    assert "faces examined for fillets 11/11" in capsys.readouterr().err
    assert main(["classify", part, "--no-axes", "-q"]) == 0
    assert capsys.readouterr().err == ""


def test_logging_state_restored_after_a_command(samples, tmp_path):
    lib = logging.getLogger("medax")
    before = (list(lib.handlers), lib.level, logging.getLogger("medax.cli").level)
    assert _mesh(samples, tmp_path, "-vv") == 0
    assert (list(lib.handlers), lib.level, logging.getLogger("medax.cli").level) == before


def test_log_progress_about_ten_messages_and_the_last(caplog):
    log = logging.getLogger("medax.test_progress")
    with caplog.at_level(logging.INFO, logger="medax"):
        for k in range(1, 106):
            log_progress(log, "items", k, 105)
    msgs = [r.getMessage() for r in caplog.records]
    assert msgs[0] == "items 10/105" and msgs[-1] == "items 105/105" and len(msgs) == 11


def test_a_command_inside_a_command_keeps_the_outer_levels(samples, tmp_path, capsys):
    """``medax demo`` runs ``main`` again: its messages are neither doubled nor shown
    under ``-q``."""
    from medax.cli.main import configure_logging

    with configure_logging(quiet=1):
        assert _mesh(samples, tmp_path) == 0
    assert capsys.readouterr().err == ""
    with configure_logging():
        assert _mesh(samples, tmp_path, "-q") == 0
    assert capsys.readouterr().err.count("medax mesh: region 'wavy'") == 1
