"""The batch's HTML reports of the demo's parts in headless Chromium: the pages load with no
script error, the 3D view renders, a screenshot shows the class colours where the faces
are, and clicking (picking) a pixel of fillet colour names a fillet face.

The parts run through :func:`medax.batch.part.work`, the body of a batch task (the Dask
side is tested in test_batch.py). Chromium is Debian's ``chromium``; it is installed when
missing (apt-get, with sudo when not root) and the tests are skipped, saying why, only when
it can be neither found nor installed. CI installs it (``.ci/run``).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from medax.batch.html import REPORT, write_report
from medax.batch.part import PartTask, work
from medax.batch.records import summarize
from medax.samples import sample_path
from medax.viz.view3d import CLASS_COLOURS

pytestmark = pytest.mark.slow

DEMO_PARTS = ("filleted-boss.step", "box-12-edges.step", "l-bracket.step")
WINDOW = (800, 600)
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    f"--window-size={WINDOW[0]},{WINDOW[1]}",
    "--virtual-time-budget=5000",
    "--no-first-run",
    "--disable-extensions",
]


def _find_chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def _install_chromium() -> str:
    """apt-get install chromium (sudo when not root); '' or the reason it failed."""
    if shutil.which("apt-get") is None:
        return "no apt-get on this machine"
    prefix: list[str] = []
    if os.geteuid() != 0:
        if shutil.which("sudo") is None:
            return "not root and no sudo"
        prefix = ["sudo", "-n"]
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    for cmd in (["apt-get", "update", "-q"], ["apt-get", "install", "-y", "-q", "chromium"]):
        run = subprocess.run([*prefix, *cmd], capture_output=True, text=True, env=env, timeout=900)
        if run.returncode != 0:
            return f"'{' '.join(cmd)}' failed: {run.stderr.strip()[-300:]}"
    return ""


@pytest.fixture(scope="module")
def chromium() -> str:
    path = _find_chromium()
    if path is None:
        why = _install_chromium()
        path = _find_chromium()
        if path is None:
            pytest.skip(f"chromium not found and not installable ({why or 'unknown reason'})")
    return path


@pytest.fixture(scope="module")
def reports(tmp_path_factory) -> Path:
    """The demo's parts classified and simplified as a batch does, and the reports."""
    out = tmp_path_factory.mktemp("batch")
    opts = {"angle": 1e-3, "tol": 1e-6, "simplify_tol": 1e-5, "pictures": False}
    records = []
    for name in DEMO_PARTS:
        part_dir = Path(name).stem
        (out / part_dir).mkdir()
        task = PartTask(
            path=str(sample_path(name)),
            sha256="0" * 64,
            options_key="0" * 16,
            outdir=str(out),
            part_dir=part_dir,
            do=("classify", "simplify"),
            options=opts,
        )
        rec = work(task)
        assert rec["status"] == "ok", rec
        records.append(rec)
    write_report(records, summarize(records, 1.0), out)
    return out


def _run(chromium: str, url: str, *args: str) -> str:
    run = subprocess.run(
        [chromium, *FLAGS, *args, url], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr[-2000:]
    return run.stdout


def _dom(chromium: str, path: Path, fragment: str = "") -> str:
    return _run(chromium, path.as_uri() + fragment, "--dump-dom")


def _errors(dom: str) -> str:
    m = re.search(r'<pre id="medax-errors"[^>]*>(.*?)</pre>', dom, re.S)
    assert m, "the page lost its error recorder"
    return m.group(1)


def _screenshot(chromium: str, path: Path, png: Path) -> np.ndarray:
    import matplotlib.image as mpimg

    _run(chromium, path.as_uri(), f"--screenshot={png}")
    img = np.asarray(mpimg.imread(png))[..., :3]
    assert img.shape[:2] == (WINDOW[1], WINDOW[0])
    return img


def _near_colour(img: np.ndarray, rgb: tuple[float, float, float]) -> np.ndarray:
    """Pixels whose colour is ``rgb`` shaded (a factor 0.3 - 1.05 of it, +- 0.04)."""
    c = np.asarray(rgb)
    k = (img @ c) / (c @ c)  # the best factor per pixel
    err = np.linalg.norm(img - k[..., None] * c, axis=-1)
    return (k > 0.3) & (k < 1.05) & (err < 0.04)


def test_reports_are_self_contained_with_the_3d_data(reports):
    run = (reports / REPORT).read_text()
    assert run.count('class="mx-model"') == 2 * len(DEMO_PARTS)  # classified + simplified
    for name in DEMO_PARTS:
        page = (reports / Path(name).stem / REPORT).read_text()
        assert page.count('class="mx-model"') == 2
        assert "http://" not in page and "https://" not in page
        assert len(page) < 400_000, len(page)  # coarse tessellation: small pages
    assert "http://" not in run and "https://" not in run
    sizes = {p.relative_to(reports): p.stat().st_size for p in reports.rglob("*.html")}
    sizes |= {p.relative_to(reports): p.stat().st_size for p in reports.rglob("*.view.json")}
    print("sizes:", {str(k): v for k, v in sorted(sizes.items())})


def test_part_report_renders_with_class_colours_and_picks_faces(chromium, reports, tmp_path):
    page = reports / "filleted-boss" / REPORT
    t0 = time.perf_counter()
    dom = _dom(chromium, page)
    assert _errors(dom).strip() == ""
    assert re.search(r'<div class="mx-view"[^>]*data-status="rendered"', dom), dom[:3000]
    rect = re.search(r'data-rect="(\d+),(\d+),(\d+),(\d+)"', dom)
    assert rect
    left, top, width, height = (int(v) for v in rect.groups())
    img = _screenshot(chromium, page, tmp_path / "part.png")
    inside = np.zeros(img.shape[:2], bool)
    inside[top : top + height, left : left + width] = True
    fillet = _near_colour(img, CLASS_COLOURS["fillet"]) & inside
    support = _near_colour(img, CLASS_COLOURS["supporting"]) & inside
    # the plate's top (supporting) fills a large share of the view, the two fillets less
    assert support.sum() > 20_000, support.sum()
    assert fillet.sum() > 1_500, fillet.sum()
    print(f"screenshot: {support.sum()} supporting, {fillet.sum()} fillet pixels")
    # click on a fillet pixel (the middle of the fillet pixels' largest row run)
    ys, xs = np.nonzero(fillet)
    k = np.argsort(ys * 10_000 + xs)[len(ys) // 2]
    fx, fy = (xs[k] + 0.5 - left) / width, (ys[k] + 0.5 - top) / height
    picked = _dom(chromium, page, f"#click={fx:.4f},{fy:.4f}")
    info = re.search(r'class="mx-info" data-face="(\d+)" data-label="(\w+)">([^<]*)<', picked)
    assert info, picked[-3000:]
    assert info.group(2) == "fillet" and "radius 2" in info.group(3), info.group(3)
    classes = json.loads((reports / "filleted-boss" / "classify.json").read_text())
    face = classes["solids"][0]["faces"][int(info.group(1))]
    assert face["class"] == "fillet"
    assert f"neighbours {', '.join(map(str, face['neighbours']))}" in info.group(3)
    print(f"chromium: 3 page loads in {time.perf_counter() - t0:.1f} s")


def test_drag_orbits_and_the_wheel_zooms(chromium, reports):
    """Mouse input replayed through the viewer's handlers: a drag of 100 px to the right
    turns the camera by 1 rad about the vertical, 40 px down tilts it by 0.4 rad, and a
    wheel of -500 brings it closer by exp(-0.5)."""
    dom = _dom(chromium, reports / "box-12-edges" / REPORT, "#drag=100,40&wheel=-500")
    assert _errors(dom).strip() == ""
    first = re.search(r'data-first-camera="([^"]+)"', dom)
    now = re.search(r'data-camera="([^"]+)"', dom)
    assert first and now
    y0, p0, d0 = (float(v) for v in first.group(1).split(","))
    y1, p1, d1 = (float(v) for v in now.group(1).split(","))
    assert y1 - y0 == pytest.approx(-1.0, abs=1e-4)
    assert p1 - p0 == pytest.approx(0.4, abs=1e-4)
    assert d1 / d0 == pytest.approx(np.exp(-0.5), rel=1e-4)


def test_run_report_loads_without_errors(chromium, reports):
    dom = _dom(chromium, reports / REPORT)
    assert _errors(dom).strip() == ""
    views = re.findall(r'<div class="mx-view" id="view" data-status="(\w+)"', dom)
    assert views == ["rendered"]
    assert "filleted-boss: classified" in dom
