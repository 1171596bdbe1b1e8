"""Images from Python: the pixels `limn render` writes, as an (h, w, 4) array."""

import numpy as np
import pytest

import limn


def test_render_equals_the_cli(tmp_path, cli):
    mesh = limn.shape("torus")
    limn.write_mesh(mesh, tmp_path / "torus.obj")
    expected = cli("render", tmp_path / "torus.obj", "-o", tmp_path / "cli.png", "--resolution",
                   "160x96", "--wireframe", "--samples", 1, json_out=True)
    result = limn.render(mesh, resolution=(160, 96), wireframe=True, samples=1)
    assert result.image.shape == (96, 160, 4) and result.image.dtype == np.uint8
    assert np.array_equal(result.image, limn.read_png(tmp_path / "cli.png"))
    for key in ("camera", "drawn", "triangles", "resolution", "renderer"):
        assert result.stats[key] == expected[key], key
    # The white background where the torus is not, the shaded torus over much of the frame.
    assert (result.image[0, 0, :3] == 255).all()
    assert 0.05 < (result.image[..., :3] < 250).any(axis=2).mean() < 0.95


def test_camera_round_trips_and_png_files(tmp_path):
    mesh = limn.shape("cube")
    first = limn.render(mesh, resolution="64x48", samples=1, background=(0, 0, 0))
    again = limn.render(mesh, resolution="64x48", samples=1, background=(0, 0, 0),
                        camera=first.stats["camera"])
    assert np.array_equal(first.image, again.image)
    limn.write_png(tmp_path / "cube.png", first.image)
    assert np.array_equal(limn.read_png(tmp_path / "cube.png"), first.image)
    with pytest.raises(limn.InputError, match="uv_checker: the mesh has no UVs"):
        limn.render(mesh, resolution="8x8", uv_checker=4)
    with pytest.raises(limn.InputError, match="samples"):
        limn.render(mesh, samples=0)
    with pytest.raises(limn.InputError, match="fovy"):
        limn.render(mesh, camera=(0, 0, 5, 0, 0, 0, 200))
    with pytest.raises(limn.InputError, match="bad.png: not a readable image"):
        (tmp_path / "bad.png").write_bytes(b"not a png")
        limn.read_png(tmp_path / "bad.png")


def test_patch_render_equals_the_cli(tmp_path, cli):
    cage = limn.shape("torus")
    limn.write_mesh(cage, tmp_path / "torus.obj")
    expected = cli("render", tmp_path / "torus.obj", "-o", tmp_path / "cli.png", "--adaptive",
                   "--depth", 3, "--depth-colors", "--wireframe", "--resolution", "160x96",
                   "--samples", 1, json_out=True)
    result = limn.patches(cage, depth=3).render(resolution=(160, 96), depth_colors=True,
                                                wireframe=True, samples=1)
    assert np.array_equal(result.image, limn.read_png(tmp_path / "cli.png"))
    for key in ("camera", "drawn", "patches", "triangles"):
        assert result.stats[key] == expected[key], key
    fixed = limn.patches(cage, depth=3).render(resolution=(64, 48), tess=2, samples=1)
    assert fixed.stats["triangles"] > 0
    with pytest.raises(limn.InputError, match="tess 40"):
        limn.patches(cage, depth=3).render(tess=40)
