"""The CLI's jobs from Python: the same meshes and reports as `limn ... --json`, the GIL released
while they run."""

import threading
import time

import numpy as np
import pytest

import limn

TIMING_KEYS = {"timings_ms"}
FILE_KEYS = {"input", "output", "dropped", "repair", "labels"}


def without(report, keys):
    return {k: v for k, v in report.items() if k not in keys}


@pytest.mark.parametrize("name,args", [
    ("spot", dict(proxies=60)),
    ("fandisk", dict(proxies=40, polygons=True)),
    ("spot", dict(target_error=0.002, method="lloyd", seeding="random", seed=3)),
])
def test_simplify_equals_the_cli(tmp_path, models, cli, name, args):
    src = models / "tri" / f"{name}.obj"
    flags = []
    for key, value in args.items():
        flag = "--" + key.replace("_", "-")
        flags += [flag] if value is True else [flag, value]
    out, labels = tmp_path / "cli.obj", tmp_path / "labels.txt"
    expected = cli("simplify", src, "-o", out, "--labels", labels, *flags, json_out=True)
    result = limn.simplify(limn.read_mesh(src), **args)
    assert without(result.stats, TIMING_KEYS) == without(expected, TIMING_KEYS | FILE_KEYS)
    limn.write_mesh(result.mesh, tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == out.read_bytes()
    assert np.array_equal(result.labels, np.loadtxt(labels, dtype=np.uint32))
    # Per output face and vertex: clusters in range, vertices copied from the input.
    assert result.face_cluster.shape == (result.mesh.face_count,)
    assert result.face_cluster.max() < result.stats["clusters"]
    source = limn.read_mesh(src).positions[result.vertex_source]
    assert np.array_equal(source, result.mesh.positions)


def test_simplify_distance_and_bad_options(models):
    mesh = limn.read_mesh(models / "tri" / "spot.obj")
    result = limn.simplify(mesh, proxies=30, distance=5000)
    assert result.stats["distance"]["samples"] == 5000
    assert 0 < result.stats["distance"]["hausdorff"] < 0.2
    with pytest.raises(limn.InputError, match="proxies 0"):
        limn.simplify(mesh, proxies=0)
    with pytest.raises(limn.InputError, match="method 'newton'|method newton"):
        limn.simplify(mesh, method="newton")
    with pytest.raises(limn.InputError, match="target_error"):
        limn.simplify(mesh, target_error=-1)


@pytest.mark.parametrize("limit", [False, True])
def test_subdivide_equals_the_cli(tmp_path, cli, limit):
    cage = limn.shape("cage")
    limn.write_mesh(cage, tmp_path / "cage.obj")
    flags = ["--limit"] if limit else []
    expected = cli("subdivide", tmp_path / "cage.obj", "-o", tmp_path / "cli.obj", "--uniform", 2,
                   *flags, json_out=True)
    result = limn.subdivide(cage, uniform=2, limit=limit)
    for key in ("level", "limit", "levels", "output_vertices", "output_faces"):
        assert result.stats[key] == expected[key], key
    limn.write_mesh(result.mesh, tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()
    with pytest.raises(limn.InputError, match="uniform 9"):
        limn.subdivide(cage, uniform=9)


def test_repair_equals_the_cli(tmp_path, cli):
    # A cube soup: every face its own vertices, one face flipped, one duplicate.
    cube = limn.shape("cube")
    corners = cube.positions[cube.face_vertices]
    faces = np.arange(len(corners)).reshape(-1, 4)
    faces[2] = faces[2][::-1]
    faces = np.vstack([faces, faces[:1]])
    soup = limn.Mesh.from_arrays(corners, faces)
    limn.write_mesh(soup, tmp_path / "soup.obj")
    expected = cli("repair", tmp_path / "soup.obj", "-o", tmp_path / "cli.obj", json_out=True)
    result = limn.repair(soup)
    assert result.stats == expected["repair"]
    assert result.stats["flipped_faces"] == 1 and result.stats["duplicate_faces"] == 1
    limn.write_mesh(result.mesh, tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()
    assert limn.info(result.mesh)["closed"]


def test_long_calls_release_the_gil():
    cage = limn.shape("torus-dense-small")
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    thread = threading.Thread(target=count)
    thread.start()
    try:
        time.sleep(0.05)
        start = time.perf_counter()
        result = limn.subdivide(cage, uniform=4)
        end = time.perf_counter()
    finally:
        stop.set()
        thread.join()
    assert end - start > 0.05, "the call was too short to tell"
    during = [t for t in ticks if start < t < end]
    # With the GIL held the counter stalls for the whole call (one tick at most); released, it
    # ticks on, though it shares the cores with the call's threads (and another test under
    # ctest -j2), so a tenth of the ticks an idle machine would give is asked for.
    assert len(during) >= 0.1 * (end - start) / 0.0011
    assert result.mesh.face_count == cage.corner_count * 4 ** 3


def test_the_worked_example_in_the_docs_runs(tmp_path, monkeypatch):
    import pathlib
    import re

    doc = pathlib.Path(__file__).parents[2] / "docs" / "python.md"
    blocks = re.findall(r"```python\n(.*?)```", doc.read_text(), re.S)
    assert blocks
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        exec(compile(code, str(doc), "exec"), {})
    cage = limn.read_mesh(tmp_path / "cage.obj")
    assert 0 < cage.face_count <= 60 * 4
    assert limn.info(limn.read_mesh(tmp_path / "smooth.obj"))["manifold"]
    for name in ("scan", "cage", "smooth", "painted"):
        assert limn.read_png(tmp_path / f"{name}.png").shape == (300, 480, 4)
    # The paint shows: red where the plain surface is grey.
    plain = limn.read_png(tmp_path / "smooth.png").astype(int)
    red = limn.read_png(tmp_path / "painted.png").astype(int)
    assert ((red[..., 0] - red[..., 1] > 60) & (plain[..., 0] - plain[..., 1] < 20)).any()
    assert limn.load_texture(tmp_path / "smooth.lot").stats["painted_samples"] > 0


@pytest.mark.parametrize("limit", [False, True])
def test_stencils_animate_a_cage_without_refining_again(limit):
    cage = limn.shape("cage")
    result = limn.stencils(cage, uniform=2, limit=limit)
    table, mesh = result.table, result.mesh
    assert table.size == mesh.vertex_count and table.source_count <= cage.vertex_count
    assert np.allclose(table.apply(cage.positions), mesh.positions, atol=1e-5)
    # A new pose of the cage: the table gives what refining the posed cage gives.
    posed = cage.copy()
    p = posed.positions
    angle = p[:, 2:3] * 0.7
    x, y = p[:, 0:1].copy(), p[:, 1:2].copy()
    p[:, 0:1], p[:, 1:2] = x * np.cos(angle) - y * np.sin(angle), x * np.sin(angle) + y * np.cos(
        angle)
    again = limn.subdivide(posed, uniform=2, limit=limit).mesh
    assert np.allclose(table.apply(posed.positions), again.positions, atol=1e-5)
    # Any per-point data: colours too.
    rgba = np.random.default_rng(0).random((cage.vertex_count, 4)).astype(np.float32)
    assert table.apply(rgba).shape == (table.size, 4)
    assert not table.weights.flags.owndata and table.weights.base is not None  # a view
    with pytest.raises(limn.InputError, match="rows, the table reads"):
        table.apply(cage.positions[:3])


def test_patches_evaluate_and_tessellate_as_the_cli(tmp_path, cli):
    cage = limn.shape("torus")
    table = limn.patches(cage, depth=3)
    assert table.regular_count > 0 and table.gregory_count > 0
    # Tessellation: the mesh `limn subdivide --adaptive --depth 3 --tess 4` writes.
    limn.write_mesh(cage, tmp_path / "torus.obj")
    cli("subdivide", tmp_path / "torus.obj", "-o", tmp_path / "cli.obj", "--adaptive", "--depth",
        3, "--tess", 4)
    limn.write_mesh(table.tessellate(tess=4), tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()
    # The limit at each cage quad's first corner, (u, v) = (0, 0) of its ptex face, is the limit
    # of that vertex, which the limit stencils (another path: limit masks) give too.
    quads = cage.faces
    ptex = table.ptex_of_face[:-1]
    zeros = np.zeros(len(ptex), np.float32)
    pos, du, dv = table.evaluate(ptex, zeros, zeros)
    limit = limn.stencils(cage, uniform=1, limit=True)
    level1 = limit.table.apply(cage.positions)
    edges = limn.info(cage)["edges"]
    first_child = cage.face_count + edges  # level 1: face points, edge points, vertex points
    assert np.allclose(pos, level1[first_child + quads[:, 0]], atol=1e-5)
    # Derivatives: central differences along u and v inside a face.
    h = 1e-3
    at = np.full(len(ptex), 0.5, np.float32)
    p0, du0, dv0 = table.evaluate(ptex, at, at)
    pu, _, _ = table.evaluate(ptex, at + h, at)
    pv, _, _ = table.evaluate(ptex, at, at + h)
    assert np.allclose((pu - p0) / h, du0, atol=2e-2 * np.abs(du0).max())
    assert np.allclose((pv - p0) / h, dv0, atol=2e-2 * np.abs(dv0).max())
    # An animated cage: update the points, evaluate again.
    moved = cage.positions * 2
    table.update(moved)
    assert np.allclose(table.evaluate(ptex, zeros, zeros)[0], 2 * pos, atol=1e-4)
    with pytest.raises(limn.InputError, match="outside"):
        table.evaluate([0], [1.5], [0.0])
    with pytest.raises(limn.InputError, match="out of range"):
        table.evaluate([table.ptex_count], [0.5], [0.5])
    with pytest.raises(limn.InputError, match="depth 13"):
        limn.patches(cage, depth=13)


def test_view_dependent_depths_as_the_cli(tmp_path, cli):
    cage = limn.shape("torus")
    limn.write_mesh(cage, tmp_path / "torus.obj")
    camera = (0.2, -3.5, 1.2, 0.0, 0.0, 0.0, 40.0)
    view = ["--camera", ",".join(map(str, camera)), "--resolution", "640x400", "--tess", 4]
    # Measured errors on a hierarchy.
    cli("subdivide", tmp_path / "torus.obj", "-o", tmp_path / "measured.obj", "--adaptive",
        "--tolerance", 0.5, "--max-depth", 6, "--errors", "measured", *view)
    h = limn.patch_hierarchy(cage, max_depth=6)
    depths = h.select_depths(camera=camera, resolution=(640, 400), tolerance=0.5)
    assert depths.dtype == np.uint8 and depths.shape == (cage.vertex_count,)
    assert 0 < depths.max() <= 6
    limn.write_mesh(h.select(depths).tessellate(tess=4), tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "measured.obj").read_bytes()
    # Estimated errors: depths for build_patches.
    cli("subdivide", tmp_path / "torus.obj", "-o", tmp_path / "estimated.obj", "--adaptive",
        "--tolerance", 0.5, "--max-depth", 6, "--errors", "estimated", *view)
    est = limn.select_depths(cage, camera=camera, resolution="640x400", tolerance=0.5,
                             max_depth=6)
    limn.write_mesh(limn.patches(cage, depth=6, vertex_depth=est).tessellate(tess=4),
                    tmp_path / "py_est.obj")
    assert (tmp_path / "py_est.obj").read_bytes() == (tmp_path / "estimated.obj").read_bytes()
    # A closer camera needs at least the same depths; the far side of the torus no more.
    near = h.select_depths(camera=(0.1, -2.0, 0.6, 0, 0, 0, 40), resolution=(640, 400))
    assert near.max() >= depths.max()
    with pytest.raises(limn.InputError, match="tolerance"):
        h.select_depths(tolerance=0)


def test_selections_share_their_hierarchy_and_its_pose():
    cage = limn.shape("torus")
    h = limn.patch_hierarchy(cage, max_depth=4)
    far = h.select(np.full(cage.vertex_count, 1, np.uint8))
    near = h.select(np.full(cage.vertex_count, 4, np.uint8))
    ptex = far.ptex_of_face[:-1]
    half = np.full(len(ptex), 0.5, np.float32)
    before = near.evaluate(ptex, half, half)[0]
    far.update(cage.positions + np.float32([0, 0, 1]))  # a pose set through one selection
    after = near.evaluate(ptex, half, half)[0]
    assert np.allclose(after, before + np.float32([0, 0, 1]), atol=1e-4)


@pytest.mark.parametrize("args", [dict(size=256), dict(size=64, tiles=12, texels_per_unit=24.0)])
def test_unwrap_equals_the_cli(tmp_path, cli, args):
    torus = limn.shape("torus")
    limn.write_mesh(torus, tmp_path / "torus.obj")
    flags = []
    for key, value in args.items():
        flags += ["--" + key.replace("_", "-"), value]
    expected = cli("unwrap", tmp_path / "torus.obj", "-o", tmp_path / "cli.obj", *flags,
                   json_out=True)
    result = limn.unwrap(torus, **args)
    assert without(result.stats, TIMING_KEYS) == without(expected, TIMING_KEYS | FILE_KEYS | {"faces"})
    limn.write_mesh(result.mesh, tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()
    # Charts and tiles as the UVs say: every face's UVs lie in its chart's tile.
    assert result.face_chart.shape == (torus.face_count,)
    assert result.chart_tile.shape == (result.stats["charts"],)
    uv = result.mesh.uvs[result.mesh.uv_indices]
    tile = result.chart_tile[np.repeat(result.face_chart, np.diff(result.mesh.face_offsets))]
    assert np.all(uv[:, 0] >= tile % 10) and np.all(uv[:, 0] <= tile % 10 + 1)
    assert np.all(uv[:, 1] >= tile // 10) and np.all(uv[:, 1] <= tile // 10 + 1)
    assert result.stats["check"]["flipped"] == 0
    assert result.stats["check"]["overlapping_texels"] == 0


def test_unwrap_bad_options_and_meshes():
    torus = limn.shape("torus")
    with pytest.raises(limn.InputError, match="max_stretch 0.5"):
        limn.unwrap(torus, max_stretch=0.5)
    with pytest.raises(limn.InputError, match="texels_per_unit"):
        limn.unwrap(torus, texels_per_unit=-2)
    with pytest.raises(limn.InputError, match="too dense"):
        limn.unwrap(torus, size=64, texels_per_unit=1000)
    fin = limn.Mesh.from_arrays(
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], np.float32),
        np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]], np.uint32))
    with pytest.raises(limn.RepairableError):
        limn.unwrap(fin)
