"""Every valid region meshes (issue 24): 300 random valid regions (line, arc, B-spline and
polyline sides; convex and non-convex; scales 1e-3 to 1e3; a fixed seed:
``tests/region_catalogue.py``), each through ``medax mesh --divisions 16`` and ``--divisions
7,23``. Each run either writes a mesh whose every corner turns counter-clockwise and whose
boundary nodes lie on their sides, both measured here from the written file (meshio, own
cross products, own dense distances), or refuses with a non-zero exit and a message naming
the corner or side in the way. Refusals stay under 2 % of the regions; on the refused ones
gmsh's transfinite mesh is made too and its inverted count printed (recorded only).

Also the untangling stage on its own: a valid grid is left as it is, a folded one is
untangled locally with its boundary nodes on their sides, and a reflex corner is refused
by name."""

from __future__ import annotations

import json
import re

import meshio
import numpy as np
import pytest

from medax.cli.main import main
from medax.errors import MeshError
from medax.geometry.curve import Curve
from medax.geometry.region import Region
from medax.geometry.region_io import region_from_dict
from medax.mesh.grid import boundary_indices, structured_quads
from medax.mesh.mesher import mesh_region
from medax.mesh.untangle import DEGENERATE_SJ, free_nodes, scaled_jacobian, untangle_grid
from region_catalogue import corner_angles, valid_regions

N_REGIONS = 300
DIVISIONS = ("16", "7,23")
#: a refusal names what is in the way
OBSTACLE = re.compile(r"(corner|side|sides) \d")


def corner_crosses(points: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """(m, 4) cross products of each quad corner's two edges (next - P) x (prev - P)."""
    q = points[quads][..., :2]
    a = np.roll(q, -1, axis=1) - q
    b = np.roll(q, 1, axis=1) - q
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def side_gap(points: np.ndarray, curve: Curve, n: int = 4000) -> tuple[np.ndarray, float]:
    """Distances (k,) from ``points`` (k, 2) to ``curve`` sampled at ``n`` parameters and its
    breaks (segments between samples), and the sampling's own error bound (twice the
    largest distance from a mid-parameter point to its chord)."""
    t = np.union1d(np.linspace(0.0, 1.0, n), curve.breaks())
    s = curve.evaluate(t)
    a, d = s[:-1], np.diff(s, axis=0)
    dd = np.maximum(np.sum(d * d, axis=1), 1e-300)

    def to_chords(p: np.ndarray) -> np.ndarray:
        u = np.clip(np.einsum("kmd,md->km", p[:, None, :] - a[None], d) / dd, 0.0, 1.0)
        foot = a[None] + u[..., None] * d[None]
        return np.sqrt(np.min(np.sum((foot - p[:, None, :]) ** 2, axis=2), axis=1))

    mid = curve.evaluate(0.5 * (t[:-1] + t[1:]))
    uu = np.clip(np.sum((mid - a) * d, axis=1) / dd, 0.0, 1.0)
    sag = float(np.max(np.linalg.norm(a + uu[:, None] * d - mid, axis=1)))
    return to_chords(np.asarray(points, dtype=np.float64)), 2.0 * sag


def check_written(path, region: Region, n1: int, n2: int) -> tuple[float, float]:
    """Read the written mesh back: all (n1 * n2) quads with every corner counter-clockwise,
    the nodes of the lines of group ``S<k>`` on side k; returns (min, p5) of the scaled
    Jacobian computed from the file."""
    m = meshio.read(path)
    quads = np.concatenate([c.data for c in m.cells if c.type == "quad"])
    assert quads.shape == (n1 * n2, 4)
    pts = m.points[:, :2]
    cross = corner_crosses(pts, quads)
    assert np.all(cross > 0.0), f"{np.count_nonzero(np.any(cross <= 0, axis=1))} inverted"
    line_blocks = [i for i, c in enumerate(m.cells) if c.type == "line"]
    group = m.cell_data["curve_group"]
    diag = region.diagonal
    for k in range(4):
        nodes = np.unique(
            np.concatenate([m.cells[i].data[group[i] == k].ravel() for i in line_blocks])
        )
        assert nodes.size == (n1 if k % 2 == 0 else n2) + 1
        gap, bound = side_gap(pts[nodes], region.sides[k])
        assert np.max(gap) <= bound + 1e-12 * diag, (k, float(np.max(gap) / diag))
    q = pts[quads]
    a = np.roll(q, -1, axis=1) - q
    b = np.roll(q, 1, axis=1) - q
    sj = np.min(cross / (np.linalg.norm(a, axis=2) * np.linalg.norm(b, axis=2)), axis=1)
    return float(sj.min()), float(np.percentile(sj, 5.0))


def gmsh_inverted(region: Region, n1: int, n2: int) -> str:
    """gmsh transfinite on the region: its inverted quads (or its error), for the record."""
    from medax.mesh.gmsh_transfinite import gmsh_transfinite

    try:
        pts, quads = gmsh_transfinite(region, n1, n2)
    except Exception as err:  # noqa: BLE001 (gmsh's own failure is what we record)
        return f"gmsh failed: {err}"
    bad = int(np.count_nonzero(np.any(corner_crosses(pts, quads) <= 0.0, axis=1)))
    return f"gmsh TFI {bad} of {len(quads)} quads inverted"


@pytest.fixture(scope="module")
def catalogue() -> list[tuple[int, dict, Region]]:
    return valid_regions(N_REGIONS)


@pytest.mark.slow
@pytest.mark.parametrize("half", [0, 1])
def test_random_regions_mesh_or_refuse_by_name(catalogue, half, tmp_path, capsys):
    """Each half of the catalogue (two halves so that two workers share the work): fewer
    than 2 % of its regions refused, so fewer than 2 % of all of them."""
    size = N_REGIONS // 2
    regions = catalogue[half * size : (half + 1) * size]
    refused: list[tuple[int, str, str]] = []
    written = 0
    for seed, spec, region in regions:
        src = tmp_path / "r.json"
        src.write_text(json.dumps({"r": spec}))
        for div in DIVISIONS:
            n1, n2 = (int(v) for v in (div.split(",") * 2)[:2])
            out = tmp_path / "m.vtu"
            code = main(["mesh", str(src), "--divisions", div, "-o", str(out)])
            err = capsys.readouterr().err
            if code != 0:
                assert not out.exists(), (seed, div)
                assert OBSTACLE.search(err), (seed, div, err)
                refused.append((seed, div, err.strip()))
                continue
            check_written(out, region, n1, n2)
            out.unlink()
            written += 1
    lines = []
    for seed, div, err in refused:
        n1, n2 = (int(v) for v in (div.split(",") * 2)[:2])
        region = next(r for s, _, r in regions if s == seed)
        lines.append(f"region {seed} --divisions {div}: {err} | {gmsh_inverted(region, n1, n2)}")
    with capsys.disabled():
        print(f"\nhalf {half}: {written} meshes written, {len(refused)} refused")
        print("\n".join(lines))
    refused_regions = {seed for seed, _, _ in refused}
    assert len(refused_regions) < 0.02 * size, sorted(refused_regions)


@pytest.fixture(scope="module")
def reflex_region() -> tuple[dict, Region]:
    (_, spec, region), *_ = valid_regions(1, reflex=True)
    return spec, region


def test_reflex_corner_is_refused_by_name(reflex_region, tmp_path, capsys):
    spec, region = reflex_region
    k = int(np.argmax(corner_angles(region)))
    with pytest.raises(MeshError, match=f"reflex corner {k} between sides"):
        mesh_region(region, divisions=(16, 16))
    src, out = tmp_path / "r.json", tmp_path / "m.vtu"
    src.write_text(json.dumps({"r": spec}))
    assert main(["mesh", str(src), "--divisions", "16", "-o", str(out)]) == 1
    assert f"reflex corner {k}" in capsys.readouterr().err and not out.exists()
    # --allow-inverted still writes it (inverted, as asked)
    assert main(["mesh", str(src), "--divisions", "16", "-o", str(out), "--allow-inverted"]) == 0
    assert out.exists()


def unit_square() -> Region:
    spec = {"corners": [[0, 0], [1, 0], [1, 1], [0, 1]], "sides": [{"kind": "line"}] * 4}
    return region_from_dict(spec, "square")


def square_grid(n: int) -> np.ndarray:
    x, y = np.meshgrid(np.linspace(0.0, 1.0, n + 1), np.linspace(0.0, 1.0, n + 1))
    return np.column_stack((x.ravel(), y.ravel()))


def test_valid_grid_is_left_as_it_is():
    p = square_grid(8)
    p[4 * 9 + 4] += [0.05, 0.03]  # distorted, not degenerate
    info: dict = {}
    out = untangle_grid(p, 8, 8, unit_square().sides, info=info)
    assert out is p and "untangle" not in info


def test_folded_grid_is_untangled_locally_on_its_sides():
    n = 12
    p = square_grid(n)
    row = n + 1
    p[6 * row + 6] = [0.9, 0.2]  # an interior node thrown across its neighbours
    p[0 * row + 5, 0] = 0.62  # a node on S0 moved past its neighbour (along the side)
    quads = structured_quads(n, n)
    assert scaled_jacobian(p, quads).min() < 0.0
    info: dict = {}
    out = untangle_grid(p, n, n, unit_square().sides, info=info)
    sj = scaled_jacobian(out, quads)
    assert sj.min() > 0.1, info
    rims = boundary_indices(n, n)
    assert np.all(out[rims[0], 1] == 0.0) and np.all(out[rims[1], 0] == 1.0)
    assert np.all(out[rims[2], 1] == 1.0) and np.all(out[rims[3], 0] == 0.0)
    corners = [r[0] for r in rims]
    np.testing.assert_array_equal(out[corners], p[corners])
    # nodes beyond the halo around the bad quads kept their places
    rings = int(re.search(r"halo (\d+)", info["untangle"]["option"]).group(1))
    bad = scaled_jacobian(p, quads) <= DEGENERATE_SJ
    kept = np.setdiff1d(np.arange(len(p)), free_nodes(bad, n, n, rings))
    assert kept.size > 0
    np.testing.assert_array_equal(out[kept], p[kept])
    assert info["untangle"]["min_sj"] == pytest.approx(sj.min())


def test_random_region_with_tangled_medial_grid_is_untangled():
    """The first catalogue region whose ratio grid has an inverted quad at 16x16 (measured
    with the stage off) meshes without one, boundary nodes on their sides."""
    for _, _, region in valid_regions(40):
        mesh = mesh_region(region, divisions=(16, 16))
        if "untangle" in mesh.info and mesh.info["untangle"]["start_min_sj"] <= 0.0:
            break
    else:
        pytest.fail("no tangled medial grid among the first 40 regions")
    assert np.all(corner_crosses(mesh.points, mesh.quads) > 0.0)
    for k, idx in enumerate(boundary_indices(16, 16)):
        gap, bound = side_gap(mesh.points[idx], region.sides[k])
        assert np.max(gap) <= bound + 1e-12 * region.diagonal


def test_region_from_dict_rejects_what_the_catalogue_skips():
    """The catalogue's validity is region_from_dict's: a bow tie is refused there."""
    from medax.errors import InputError

    spec = {"corners": [[0, 0], [1, 1], [1, 0], [0, 1]], "sides": [{"kind": "line"}] * 4}
    with pytest.raises(InputError):
        region_from_dict(spec, "bowtie")


@pytest.fixture(scope="module")
def shared_regions() -> dict[str, Region]:
    from medax.geometry import read_regions, sample_regions_path

    return read_regions(sample_regions_path())


def test_smooth_lifts_wavy_to_gmsh_smoothed_and_keeps_polar_grid(shared_regions):
    """``smooth=True`` on wavy at 32x32: the 5th-percentile scaled Jacobian rises above the
    unsmoothed grid's and is at least gmsh TFI + Mesh.Smoothing = 100's (measured here);
    the annulus sector's exact polar grid is left as it is (the pass would lower it)."""
    from medax.mesh.gmsh_transfinite import gmsh_transfinite

    wavy = shared_regions["wavy"]
    plain = mesh_region(wavy, divisions=(32, 32), smooth=False)
    smooth = mesh_region(wavy, divisions=(32, 32), smooth=True)
    p5 = [np.percentile(m.quality().scaled_jacobian, 5) for m in (plain, smooth)]
    gp, gq = gmsh_transfinite(wavy, 32, 32, smoothing=100)
    gmsh_p5 = np.percentile(scaled_jacobian(gp, gq), 5)
    assert smooth.info["smooth"]["kept"] and p5[1] > p5[0] and p5[1] >= gmsh_p5
    assert smooth.quality().scaled_jacobian.min() >= plain.quality().scaled_jacobian.min()
    for idx in boundary_indices(32, 32):  # boundary nodes unchanged
        np.testing.assert_array_equal(smooth.points[idx], plain.points[idx])
    sector = shared_regions["annulus_sector"]
    a = mesh_region(sector, divisions=(16, 16), smooth=False)
    b = mesh_region(sector, divisions=(16, 16), smooth=True)
    assert not b.info["smooth"]["kept"]
    np.testing.assert_array_equal(a.points, b.points)


def test_cli_smooth_refused_on_parts(tmp_path, capsys):
    step = tmp_path / "p.step"
    step.write_text("not read")
    assert main(["mesh", str(step), "--size", "1", "-o", str(tmp_path / "m.msh"), "--smooth"])
    assert "--smooth and --no-smooth apply to regions" in capsys.readouterr().err
