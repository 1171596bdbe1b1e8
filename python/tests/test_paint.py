"""Octree textures from Python: the CLI's paint, bake and render on the same script, and
lookups at arrays of points."""

import json

import numpy as np
import pytest

import limn


def script_for(mesh):
    """A red stroke across the top of the mesh, a blue fill-free dab, and a pick on the stroke."""
    p = mesh.positions
    top = p[np.argsort(p[:, 2])[-40:]]  # points near the top
    order = np.argsort(top[:, 0])
    points = top[order][::8]
    radius = float(np.ptp(p, axis=0).max() * 0.05)
    return {"strokes": [
        {"points": points, "radius": radius, "color": [1, 0, 0, 1], "hardness": 0.5},
        {"points": p[:1], "radius": radius, "color": [0, 0, 1, 1]},
        {"type": "pick", "point": points[len(points) // 2]},
    ]}, points


@pytest.fixture(scope="module")
def painted(tmp_path_factory, cli):
    tmp = tmp_path_factory.mktemp("paint")
    mesh = limn.shape("torus")
    limn.write_mesh(mesh, tmp / "torus.obj")
    script, points = script_for(mesh)
    (tmp / "s.json").write_text(json.dumps(limn._jsonable(script)))
    expected = cli("paint", tmp / "torus.obj", "--strokes", tmp / "s.json", "-o", tmp / "cli.lot",
                   "--depth", 8, json_out=True)
    result = limn.paint(mesh, script, depth=8)
    return tmp, mesh, script, points, expected, result


def test_paint_equals_the_cli(painted):
    tmp, mesh, script, points, expected, result = painted
    result.texture.save(tmp / "py.lot")
    assert (tmp / "py.lot").read_bytes() == (tmp / "cli.lot").read_bytes()
    for key in ("strokes", "dabs", "dabs_missed", "samples_changed", "leaves_created",
                "bricks_created", "picks", "texture", "depth", "entries"):
        assert result.stats[key] == expected[key], key
    assert result.stats["picks"][0]["found"]
    assert limn.load_texture(tmp / "py.lot").stats == result.texture.stats
    # The same script from a file and from JSON text.
    again = limn.paint(mesh, tmp / "s.json", depth=8)
    assert again.texture.stats == result.texture.stats
    assert limn.paint(mesh, json.dumps(limn._jsonable(script)), depth=8).stats["dabs"] == \
        result.stats["dabs"]


def test_lookups_see_the_paint(painted):
    tmp, mesh, script, points, expected, result = painted
    colors, found = result.texture.nearest(points)
    assert found.all()
    assert (colors[:, 0] > 200).all() and (colors[:, 2] < 50).all()  # red
    far = mesh.positions[np.argsort(mesh.positions[:, 2])[:5]]  # the bottom, never painted
    colors, found = result.texture.nearest(far)
    assert (colors == 0).all()  # the transparent background
    rgba, found = result.texture.filtered(points)
    assert rgba.dtype == np.float32 and found.all() and (rgba[:, 0] > 0.7).all()
    # One lookup at a time agrees with the batch.
    singles = np.vstack([result.texture.nearest(points[i:i + 1])[0] for i in range(len(points))])
    assert np.array_equal(singles, result.texture.nearest(points)[0])


def test_bake_equals_the_lookups_and_the_cli(painted, cli):
    tmp, mesh, script, points, expected, result = painted
    colors = limn.bake(result.texture, mesh)
    assert colors.shape == (mesh.vertex_count, 4)
    looked_up, _ = result.texture.filtered(mesh.positions, mesh.vertex_normals())
    assert np.array_equal(colors, looked_up)
    cli("bake", tmp / "cli.lot", tmp / "torus.obj", "-o", tmp / "cli.ply")
    from_cli = limn.read_mesh(tmp / "cli.ply").colors
    assert np.abs(np.round(colors * 255) - np.round(from_cli * 255)).max() <= 1


def test_uv_bake_and_render_equal_the_cli(tmp_path, cli):
    cube = limn.shape("cube")
    n = cube.corner_count
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]] * (n // 4), np.float32) * 0.25
    uvs += np.repeat(np.arange(n // 4), 4)[:, None] * np.array([0.16, 0.0], np.float32)
    cube = limn.Mesh.from_arrays(cube.positions, cube.faces, uvs=uvs,
                                 uv_indices=np.arange(n))
    limn.write_mesh(cube, tmp_path / "cube.obj")
    script = {"strokes": [{"points": [[0.5, 0.5, 1.0], [-0.5, -0.5, 1.0]], "radius": 0.4,
                           "color": [0, 1, 0, 1]}]}
    (tmp_path / "s.json").write_text(json.dumps(script))
    cli("paint", tmp_path / "cube.obj", "--strokes", tmp_path / "s.json", "-o",
        tmp_path / "cube.lot", "--depth", 7)
    texture = limn.paint(cube, script, depth=7).texture
    image = limn.bake(texture, cube, uv=True, size=64, gutter=2)
    cli("bake", tmp_path / "cube.lot", tmp_path / "cube.obj", "-o", tmp_path / "cli.png",
        "--size", 64, "--gutter", 2)
    assert np.array_equal(image, limn.read_png(tmp_path / "cli.png"))
    cli("render", tmp_path / "cube.obj", "-o", tmp_path / "r.png", "--texture",
        tmp_path / "cube.lot", "--resolution", "96x64", "--samples", 1)
    shown = limn.render(cube, texture=texture, resolution=(96, 64), samples=1).image
    assert np.array_equal(shown, limn.read_png(tmp_path / "r.png"))
    assert (shown[..., 1] > shown[..., 0] + 40).any()  # green shows


def test_bad_paint_input(painted):
    tmp, mesh, script, points, expected, result = painted
    with pytest.raises(limn.InputError, match="depth 0"):
        limn.paint(mesh, script, depth=0)
    with pytest.raises(limn.InputError, match="strokes"):
        limn.paint(mesh, {"strokes": [{"points": [[0, 0, 0]], "radius": -1}]})
    with pytest.raises(limn.InputError, match="must end in .lot"):
        result.texture.save(tmp / "x.png")
    (tmp / "bad.lot").write_bytes(b"LOT nonsense")
    with pytest.raises(limn.InputError, match="bad.lot"):
        limn.load_texture(tmp / "bad.lot")


def test_a_painting_session_undoes_and_redoes(painted):
    tmp, mesh, script, points, expected, result = painted
    session = limn.Painter(mesh, depth=8)
    blank = session.texture
    session.run({"strokes": script["strokes"][:1]})
    session.run({"strokes": script["strokes"][1:2]})
    assert session.undo_count == 2
    # Stroke by stroke, the texture `paint` makes from the same two strokes.
    both = limn.paint(mesh, {"strokes": script["strokes"][:2]}, depth=8).texture
    assert session.texture.stats == both.stats
    assert session.undo() and session.undo() and not session.undo()
    assert session.texture.stats == blank.stats
    colors, _ = session.texture.nearest(points)
    assert (colors == 0).all()  # nothing left of the red stroke
    assert session.redo() and session.redo() and not session.redo()
    assert np.array_equal(session.texture.nearest(points)[0], both.nearest(points)[0])
    session.texture.save(tmp / "session.lot")
    both.save(tmp / "both.lot")
    assert (tmp / "session.lot").read_bytes() == (tmp / "both.lot").read_bytes()


def test_atlas_bakes_equal_the_cli(tmp_path, cli):
    torus = limn.shape("torus")
    limn.write_mesh(torus, tmp_path / "torus.obj")
    script = {"strokes": [{"type": "fill", "color": [0.2, 0.6, 0.3, 1]},
                          {"points": [[1.4, 0, 0], [0, 1.4, 0]], "radius": 0.3,
                           "color": [1, 0, 0, 1], "depth": 8}]}
    (tmp_path / "s.json").write_text(json.dumps(script))
    cli("paint", tmp_path / "torus.obj", "--strokes", tmp_path / "s.json", "-o",
        tmp_path / "t.lot")
    texture = limn.paint(torus, script).texture

    # One atlas into a GLB: the same bytes as `limn bake --atlas -o x.glb`.
    report = cli("bake", tmp_path / "t.lot", tmp_path / "torus.obj", "--atlas", "--size", 256,
                 "-o", tmp_path / "cli.glb", json_out=True)
    atlas = limn.unwrap(torus, size=256)
    assert limn.udim_tiles(atlas.mesh) == [1001]
    image = limn.bake(texture, atlas.mesh, uv=True, size=256)
    baked = limn.bake_material(texture, atlas.mesh, size=256)
    assert np.array_equal(baked.base_color, image)
    assert baked.metallic_roughness is None and baked.height is None and baked.normal is None
    # No channel painted: the defaults are the material's factors.
    assert (baked.roughness, baked.metallic) == (0.5, 0.0)
    limn.write_glb(atlas.mesh, tmp_path / "py.glb", base_color=image, metallic=baked.metallic,
                   roughness=baked.roughness)
    assert (tmp_path / "py.glb").read_bytes() == (tmp_path / "cli.glb").read_bytes()
    assert report["mode"] == "glb" and report["atlas"]["charts"] == atlas.stats["charts"]
    back = limn.read_mesh(tmp_path / "py.glb")
    assert back.face_count == 2 * torus.face_count and back.uvs.shape[1] == 2

    # UDIM tiles: one PNG per tile, each equal to the Python bake of that tile.
    cli("bake", tmp_path / "t.lot", tmp_path / "torus.obj", "--atlas", "--size", 64, "--tiles", 8,
        "--texels-per-unit", 20, "-o", tmp_path / "p.<UDIM>.png", "--mesh-out",
        tmp_path / "uv.obj")
    udim = limn.unwrap(torus, size=64, tiles=8, texels_per_unit=20.0)
    tiles = limn.udim_tiles(udim.mesh)
    assert len(tiles) >= 2 and tiles[0] == 1001
    for tile in tiles:
        baked = limn.bake(texture, udim.mesh, uv=True, size=64, udim=tile)
        assert np.array_equal(baked, limn.read_png(tmp_path / f"p.{tile}.png")), tile
    assert not (tmp_path / f"p.{tiles[-1] + 1}.png").exists()
    limn.write_mesh(udim.mesh, tmp_path / "py-uv.obj")
    assert (tmp_path / "py-uv.obj").read_bytes() == (tmp_path / "uv.obj").read_bytes()

    # A texture of another mesh is refused; a bad tile too.
    plane = limn.Mesh.from_arrays(
        np.array([[-1.4, 0, -1.4], [1.4, 0, -1.4], [1.4, 0, 1.4], [-1.4, 0, 1.4]], np.float32),
        np.array([[0, 1, 2, 3]], np.uint32))
    with pytest.raises(limn.InputError, match="painted on another mesh"):
        limn.bake(texture, plane)
    with pytest.raises(limn.InputError, match="udim 999"):
        limn.bake(texture, atlas.mesh, uv=True, udim=999)
