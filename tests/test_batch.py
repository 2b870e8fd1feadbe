"""``medax batch`` on a Dask LocalCluster started here on 127.0.0.1: records, outputs equal
to the single-part commands', resume, a part that hangs and a worker killed mid-task."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import threading
import time
from pathlib import Path

import pytest

from medax.batch import BatchOptions, run_batch
from medax.batch.html import report_html, write_report
from medax.batch.inputs import collect_inputs, part_dirs
from medax.batch.records import (
    RECORDS,
    append_record,
    finished_records,
    options_key,
    read_records,
    summarize,
)
from medax.cli.main import main
from medax.errors import InputError
from medax.schemas import validation_errors

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def parts(tmp_path_factory) -> Path:
    """Two filleted STEP parts built with OCCT and a file that is not a part."""
    from medax.cad.parts import l_bracket
    from medax.cad.simplify import parts as P
    from medax.cad.simplify.step_out import write_step

    d = tmp_path_factory.mktemp("parts")
    write_step(P.box_vertical_fillets().shape, d / "box4.step")
    sub = d / "sub"
    sub.mkdir()
    write_step(l_bracket().shape, sub / "bracket.step")
    (d / "broken.stp").write_text("ISO-10303-21;\nnot a part\n")
    (d / "notes.txt").write_text("not an input")
    return d


@contextlib.contextmanager
def local_cluster():
    """One worker process (one thread) on 127.0.0.1; a killed part is retried once. The
    config holds while the cluster runs: a restarted worker reads it again."""
    import dask

    config = {"distributed.worker.daemon": False, "distributed.scheduler.allowed-failures": 1}
    with dask.config.set(config):
        c = distributed.LocalCluster(
            n_workers=1,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",
        )
        with c:
            yield c


@pytest.fixture(scope="module")
def cluster():
    with local_cluster() as c:
        yield c


def lines(outdir: Path) -> list[dict]:
    return [json.loads(x) for x in (outdir / RECORDS).read_text().splitlines()]


def test_inputs_folders_globs_and_refusals(parts, tmp_path):
    found = collect_inputs([str(parts)])
    assert [p.name for p in found] == ["box4.step", "broken.stp", "bracket.step"]
    assert [p.name for p in collect_inputs([str(parts / "**" / "*.step")])] == [
        "box4.step",
        "bracket.step",
    ]
    # a file given twice (or through a folder and by name) is one part
    assert len(collect_inputs([str(parts / "box4.step"), str(parts)])) == 3
    with pytest.raises(InputError, match="no such file"):
        collect_inputs([str(tmp_path / "missing.step")])
    with pytest.raises(InputError, match="matches no"):
        collect_inputs([str(tmp_path / "*.step")])
    # the output folder is never searched
    assert collect_inputs([str(parts)], exclude=parts / "sub")[-1].name == "broken.stp"
    assert part_dirs([Path("a/x.step"), Path("b/x.stp")], ["1" * 64, "2" * 64]) == [
        "x-11111111",
        "x-22222222",
    ]


def test_options_are_checked_before_any_work(parts, tmp_path):
    with pytest.raises(InputError, match="mesh-size"):
        run_batch([str(parts)], tmp_path / "o", BatchOptions(do=("mesh",)))
    with pytest.raises(InputError, match="--do"):
        run_batch([str(parts)], tmp_path / "o", BatchOptions(do=("fillet",)))
    for bad in (
        ["--timeout", "-1"],
        ["--timeout", "nan"],
        ["--tol", "inf"],
        ["--simplify-tol", "nan"],
    ):
        assert main(["batch", str(parts), "-o", str(tmp_path / "o"), *bad]) == 1
    assert not (tmp_path / "o" / RECORDS).exists()


def test_finished_parts_are_found_by_hash_and_options(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "classify.json").write_text("{}")
    outs = {"classify_report": "a/classify.json"}
    append_record(tmp_path, {"sha256": "1", "options_key": "k", "status": "ok", "outputs": outs})
    append_record(tmp_path, {"sha256": "2", "options_key": "k", "status": "timeout"})
    append_record(tmp_path, {"sha256": "3", "options_key": "k", "status": "refused"})
    append_record(tmp_path, {"sha256": "3", "options_key": "j", "status": "ok"})
    gone = {"classify_report": "b/classify.json"}
    append_record(tmp_path, {"sha256": "4", "options_key": "k", "status": "ok", "outputs": gone})
    append_record(tmp_path, {"sha256": "5", "options_key": "k", "status": "ok"})
    append_record(tmp_path, {"sha256": "5", "options_key": "k", "status": "failed"})  # later
    assert set(finished_records(tmp_path)) == {("1", "k"), ("3", "k"), ("3", "j")}
    assert options_key(["classify"], {"tol": 1e-6}) != options_key(["classify"], {"tol": 1e-5})


def test_strict_volume_reaches_simplify_and_keeps_old_records_valid(tmp_path):
    """``--strict-volume`` is passed to each part's simplify; off, the options (and so the
    keys of the records written before it existed) are as they were."""
    from medax.batch.part import PartTask, step_argv

    plain = BatchOptions(do=("simplify",)).step_options()
    strict = BatchOptions(do=("simplify",), strict_volume=True).step_options()
    assert "strict_volume" not in plain and strict["strict_volume"] is True
    assert options_key(["simplify"], plain) != options_key(["simplify"], strict)
    for opts, want in ((plain, False), (strict, True)):
        task = PartTask("p.step", "0", "k", str(tmp_path), "p", ("simplify",), opts)
        argv, _ = step_argv("simplify", task, {})
        assert ("--strict-volume" in argv) is want


def test_journal_skips_a_torn_line(tmp_path):
    append_record(tmp_path, {"sha256": "a", "options_key": "k", "status": "ok"})
    with open(tmp_path / RECORDS, "a") as f:
        f.write('{"sha256": "b", "opt')  # a crash mid-line
    assert [r["sha256"] for r in read_records(tmp_path)] == ["a"]


def test_html_report_is_one_file_with_pictures_inlined(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    (tmp_path / "p").mkdir()
    plt.figure(figsize=(1, 1))
    plt.savefig(tmp_path / "p" / "classify.png")
    plt.close("all")
    rec = {
        "input": "<p>.step",
        "part_dir": "p",
        "status": "ok",
        "steps": {"classify": {"status": "ok", "time_s": 1.0}},
        "counts": {"faces": 7, "blends_kept": 1},
        "kept_reasons": {"too_narrow": 1},
        "outputs": {"classify_png": "p/classify.png"},
        "time_s": 1.0,
    }
    summary = summarize([rec], 2.0)
    page = report_html([rec], summary, tmp_path)
    assert "data:image/png;base64," in page and "&lt;p&gt;.step" in page
    assert "too_narrow" in page and "<script>" in page
    assert "http://" not in page and "https://" not in page and 'src="http' not in page
    assert write_report([rec], summary, tmp_path).read_text() == page


def test_run_report_embeds_3d_data_up_to_its_budget(tmp_path, monkeypatch):
    """Parts whose view data would pass the budget are left to their own reports."""
    from medax.batch import html as H

    records = []
    for name, size in (("a", 1000), ("b", 5000), ("c", 1000)):
        (tmp_path / name).mkdir()
        data = {"title": "classified", "pad": "x" * size}
        (tmp_path / name / "classify.view.json").write_text(json.dumps(data))
        records.append(
            {
                "input": f"{name}.step",
                "part_dir": name,
                "status": "ok",
                "steps": {},
                "outputs": {"classify_view": f"{name}/classify.view.json"},
                "time_s": 1.0,
            }
        )
    monkeypatch.setattr(H, "MAX_VIEW_BYTES", 4000)
    page = H.report_html(records, summarize(records, 1.0), tmp_path)
    assert page.count('class="mx-model"') == 2  # a and c; b alone is over the budget
    assert "a: classified" in page and "c: classified" in page and "b: classified" not in page
    H.write_report(records, summarize(records, 1.0), tmp_path)
    for name in "abc":  # every part's own report has its view
        assert (tmp_path / name / "report.html").read_text().count('class="mx-model"') == 1


@pytest.mark.slow
def test_batch_records_outputs_and_resume(parts, cluster, tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["batch", str(parts), "-o", str(out), "--scheduler", cluster.scheduler_address]
    argv += ["--timeout", "120"]
    assert main([*argv, "--do", "classify,simplify"]) == 0  # a refused part is not a failure
    recs = {r["part_dir"]: r for r in lines(out)}
    assert set(recs) == {"box4", "bracket", "broken"}
    for r in recs.values():
        assert validation_errors(r, "batch-record") == []
    assert recs["broken"]["status"] == "refused" and "classify" in recs["broken"]["error"]
    box = recs["box4"]
    assert box["status"] == "ok" and box["steps"]["simplify"]["status"] == "ok"
    assert box["counts"]["faces_before"] == 10 and box["counts"]["blends_removed"] == 4
    assert box["counts"]["faces_after"] == 6 and box["kept_reasons"] == {}
    for rel in box["outputs"].values():
        assert (out / rel).is_file()
    # the batch's outputs are the single-part command's
    single = tmp_path / "single.json"
    assert main(["classify", str(parts / "box4.step"), "--report", str(single)]) == 0
    mine, theirs = (
        json.loads((out / "box4" / "classify.json").read_text()),
        json.loads(single.read_text()),
    )
    assert mine["summary"] == theirs["summary"] and mine["solids"] == theirs["solids"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == {"ok": 2, "refused": 1, "failed": 0, "timeout": 0}
    assert validation_errors(summary, "batch-summary") == []
    text = capsys.readouterr()
    assert "3 parts (0 skipped" in text.out and "ETA" in text.err
    assert not list(out.rglob(".*.tmp*"))
    page = (out / "report.html").read_text()
    assert page.count("<tr class=") == 3 and 'href="box4/simplify.json"' in page
    # resume: nothing runs again, and nothing is appended
    assert main([*argv, "--do", "classify,simplify"]) == 0
    assert len(lines(out)) == 3
    assert "3 parts (3 skipped" in capsys.readouterr().out
    # a part whose output was removed runs again; the others are skipped
    (out / "bracket" / "simplify.json").unlink()
    opts = BatchOptions(scheduler=cluster.scheduler_address, timeout=120.0)
    res = run_batch([str(parts)], out, opts)
    ran = [r["part_dir"] for r in res.records if not r.get("skipped")]
    assert ran == ["bracket"] and res.exit_code == 0
    # other options: everything runs again
    res = run_batch(
        [str(parts / "box4.step")],
        out,
        BatchOptions(do=("classify",), scheduler=cluster.scheduler_address, timeout=120.0),
    )
    assert [r.get("skipped", False) for r in res.records] == [False]


@pytest.mark.slow
def test_a_hanging_part_times_out_and_the_batch_completes(parts, tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(parts / "box4.step", src / "box4.step")
    shutil.copy(parts / "sub" / "bracket.step", src / "hang.step")
    opts = BatchOptions(do=("classify",), workers=2, timeout=8.0, hook="batch_hooks:hang_if_named")
    res = run_batch([str(src)], tmp_path / "out", opts)  # the default: a local cluster
    status = {r["part_dir"]: r["status"] for r in res.records}
    assert status == {"box4": "ok", "hang": "timeout"} and res.exit_code == 3
    pid = int((src / "hang.step.pid").read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # killed, and reaped
    rec = next(r for r in res.records if r["status"] == "timeout")
    assert "timeout" in rec["error"] and not list((tmp_path / "out").rglob(".*.tmp*"))
    assert res.summary["status"]["timeout"] == 1


@pytest.mark.slow
def test_a_killed_worker_does_not_stop_the_batch(parts, tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(parts / "box4.step", src / "slow.step")
    opts = BatchOptions(do=("classify",), workers=1, hook="batch_hooks:slow_once")
    result: dict = {}
    thread = threading.Thread(
        target=lambda: result.update(res=run_batch([str(src)], tmp_path / "out", opts))
    )
    thread.start()  # on the batch's own local cluster
    marker = src / "slow.step.started"
    deadline = time.monotonic() + 120
    while not marker.exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    assert marker.exists()
    child = int(marker.read_text())
    server = parent(child)
    assert b"forkserver" in Path(f"/proc/{server}/cmdline").read_bytes()
    os.kill(parent(server), signal.SIGKILL)  # the worker, mid-task
    thread.join(180)
    assert not thread.is_alive()
    (rec,) = result["res"].records
    assert rec["status"] == "ok"  # retried on the restarted worker
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:  # the part's process dies with its worker
        try:
            os.kill(child, 0)
        except ProcessLookupError:
            break
        time.sleep(0.2)
    else:
        pytest.fail("the killed worker's part process is still running")


def parent(pid: int) -> int:
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])


@pytest.mark.slow
def test_a_part_that_kills_its_worker_twice_is_recorded_as_failed(parts, tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(parts / "box4.step", src / "crash.step")
    shutil.copy(parts / "sub" / "bracket.step", src / "bracket.step")
    opts = BatchOptions(do=("classify",), workers=1, hook="batch_hooks:kill_worker")
    res = run_batch([str(src)], tmp_path / "out", opts)  # on its own local cluster
    status = {r["part_dir"]: r["status"] for r in res.records}
    assert status == {"bracket": "ok", "crash": "failed"} and res.exit_code == 3
    crash = next(r for r in res.records if r["part_dir"] == "crash")
    assert "KilledWorker" in crash["error"]
    assert [r["part_dir"] for r in lines(tmp_path / "out")] == list(status)


def test_a_second_batch_into_the_same_folder_is_refused(parts, tmp_path):
    import fcntl

    from medax.batch.run import LOCK

    out = tmp_path / "out"
    out.mkdir()
    with open(out / LOCK, "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        with pytest.raises(InputError, match="another medax batch"):
            run_batch([str(parts)], out, BatchOptions(do=("classify",)))
    assert not (out / RECORDS).exists()


@pytest.mark.slow
def test_daemonic_workers_run_each_part_in_a_new_interpreter(parts, tmp_path):
    """A stock ``dask worker`` is a daemonic process: the part runs in ``python -m
    medax.batch.child`` instead of a fork, with the same record, timeout and outputs."""
    import dask

    src = tmp_path / "in"
    src.mkdir()
    shutil.copy(parts / "sub" / "bracket.step", src / "bracket.step")
    shutil.copy(parts / "box4.step", src / "hang.step")
    with dask.config.set({"distributed.worker.daemon": True}):
        c = distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, host="127.0.0.1", dashboard_address="127.0.0.1:0"
        )
        with c:
            opts = BatchOptions(
                do=("classify",),
                scheduler=c.scheduler_address,
                timeout=30.0,
                hook="batch_hooks:hang_if_named",
            )
            res = run_batch([str(src)], tmp_path / "out", opts)
    status = {r["part_dir"]: r["status"] for r in res.records}
    assert status == {"bracket": "ok", "hang": "timeout"}
    rec = next(r for r in res.records if r["status"] == "ok")
    assert rec["counts"]["fillets"] == 2 and rec["cpu_s"] > 0
    assert (tmp_path / "out" / rec["outputs"]["classify_report"]).is_file()
    with pytest.raises(ProcessLookupError):
        os.kill(int((src / "hang.step.pid").read_text()), 0)


@pytest.mark.slow
def test_mesh_step_meshes_the_simplified_part_and_pictures_go_in_the_report(
    parts, cluster, tmp_path
):
    out = tmp_path / "out"
    argv = ["batch", str(parts / "sub" / "bracket.step"), "-o", str(out), "--pictures"]
    argv += ["--do", "classify,simplify,mesh", "--mesh-size", "5", "--timeout", "120"]
    assert main([*argv, "--scheduler", cluster.scheduler_address]) == 0
    (rec,) = lines(out)
    assert rec["status"] == "ok" and list(rec["steps"]) == ["classify", "simplify", "mesh"]
    assert rec["counts"]["mesh_quads"] > 0
    mesh = json.loads((out / rec["outputs"]["mesh_report"]).read_text())
    assert mesh["input"].endswith("simplified.step")
    assert set(rec["outputs"]) >= {"classify_png", "simplify_png", "mesh_png", "mesh"}
    page = (out / "report.html").read_text()
    assert page.count("data:image/png;base64,") == 3
    # the mesh quality histograms: one bar per bin, the bars' counts are the quads
    hists = re.findall(r'<svg class="hist".*?</svg>', page)
    assert len(hists) == 3
    for svg in hists:
        counts = [int(n) for n in re.findall(r": (\d+) quads</title>", svg)]
        assert sum(counts) == rec["counts"]["mesh_quads"]
    # the part's own report has the 3D view of the classified and the simplified part
    own = (out / "bracket" / "report.html").read_text()
    assert own.count('class="mx-model"') == 2 and own.count('<svg class="hist"') == 3
    assert 'href="../bracket/mesh.msh"' in own
    log = (out / "bracket" / "batch.log").read_text()
    assert "$ medax mesh" in log and "wrote" in log


@pytest.mark.slow
def test_a_local_worker_whose_nanny_stopped_is_started_again():
    from medax.batch.run import revive_local_workers

    with local_cluster() as c, distributed.Client(c) as client:
        (name,) = c.workers
        c.sync(c.workers[name].close)  # as a nanny that failed to restart its worker
        deadline = time.monotonic() + 60
        while client.scheduler_info()["workers"] and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not client.scheduler_info()["workers"]
        assert revive_local_workers(c) == 1
        client.wait_for_workers(1, timeout=120)
        assert client.submit(os.getpid, pure=False).result(timeout=60) != os.getpid()
        assert revive_local_workers(c) == 0
