"""Material channels from Python: strokes carrying roughness, metallic and height, their lookups,
the material baked into an atlas and written as a GLB: the same bytes as the CLI."""

import json
import struct

import numpy as np
import pytest

import limn
from limn import batch

SCRIPT = {"strokes": [
    {"type": "fill", "color": [0.7, 0.5, 0.3, 1]},
    {"points": [[1.4, 0, 0], [0, 1.4, 0]], "radius": 0.3, "color": [0.9, 0.1, 0.1],
     "metallic": 1, "roughness": 0.2, "depth": 7},
    {"points": [[0, -1.4, 0.3], [1.0, -1.0, 0.3]], "radius": 0.25,
     "height": {"value": 1, "opacity": 0.8}, "depth": 7},
]}


@pytest.fixture(scope="module")
def material(tmp_path_factory, cli):
    tmp = tmp_path_factory.mktemp("material")
    torus = limn.shape("torus")
    limn.write_mesh(torus, tmp / "torus.obj")
    (tmp / "m.json").write_text(json.dumps(SCRIPT))
    cli("paint", tmp / "torus.obj", "--strokes", tmp / "m.json", "-o", tmp / "cli.lot",
        "--channel-defaults", "0.6,0.1,0.5", "--height-scale", 0.05)
    result = limn.paint(torus, SCRIPT, channel_defaults=(0.6, 0.1, 0.5), height_scale=0.05)
    return tmp, torus, result


def test_paint_with_channels_equals_the_cli(material):
    tmp, torus, result = material
    texture = result.texture
    assert texture.has_channels
    assert texture.height_scale == pytest.approx(0.05)
    assert texture.channel_defaults == pytest.approx((0.6, 0.1, 0.5), abs=0.51 / 255)
    assert result.stats["texture"]["rmh"]["painted_samples"] > 1000
    texture.save(tmp / "py.lot")
    assert (tmp / "py.lot").read_bytes() == (tmp / "cli.lot").read_bytes()
    back = limn.load_texture(tmp / "cli.lot")
    assert back.has_channels and back.stats == texture.stats


def test_channels_are_looked_up_over_the_defaults(material):
    _, torus, result = material
    texture = result.texture
    # On the metal stroke, and far from every stroke.
    on = np.array([[1.4, 0.0, 0.0], [0.0, 1.4, 0.0]], dtype=np.float32)
    far = np.array([[-1.4, 0.0, 0.0]], dtype=np.float32)
    c = texture.channels(on, on)
    assert c.shape == (2, 3) and c.dtype == np.float32
    assert np.allclose(c[:, 0], 0.2, atol=1.5 / 255) and np.allclose(c[:, 1], 1, atol=1.5 / 255)
    assert c[:, 2] == pytest.approx(texture.channel_defaults[2], abs=1.5 / 255)
    d = texture.channels(far, far)
    assert d[0] == pytest.approx(texture.channel_defaults, abs=1.5 / 255)
    # A colour-only texture has the defaults everywhere.
    plain = limn.paint(torus, {"strokes": [{"type": "fill", "color": [1, 1, 1, 1]}]}).texture
    assert not plain.has_channels and plain.stats["rmh"] is None
    assert plain.channels(on)[0] == pytest.approx((0.5, 0.0, 0.5))


def test_bad_channel_input(material):
    _, torus, _ = material
    with pytest.raises(limn.InputError, match="channel_defaults"):
        limn.paint(torus, SCRIPT, channel_defaults=(2, 0, 0))
    with pytest.raises(limn.InputError, match="height_scale"):
        limn.paint(torus, SCRIPT, height_scale=-1)
    with pytest.raises(limn.InputError, match=r"strokes\[0\]\.roughness"):
        limn.paint(torus, {"strokes": [{"points": [[1.4, 0, 0]], "radius": 0.2,
                                         "roughness": 3}]})


def test_material_bake_and_glb_equal_the_cli(material, cli):
    tmp, torus, result = material
    report = cli("bake", tmp / "cli.lot", tmp / "torus.obj", "--atlas", "--size", 128,
                 "--normal-map", "-o", tmp / "cli.glb", json_out=True)
    assert report["dropped"] == []
    atlas = limn.unwrap(torus, size=128)
    baked = limn.bake_material(result.texture, atlas.mesh, size=128, normal_map=True)
    assert baked.base_color.shape == (128, 128, 4)
    assert baked.metallic_roughness.shape == (128, 128, 4)
    assert baked.height.shape == (128, 128) and baked.height.dtype == np.uint16
    assert baked.normal.shape == (128, 128, 4)
    assert (baked.metallic, baked.roughness) == (1.0, 1.0)
    limn.write_glb(atlas.mesh, tmp / "py.glb", base_color=baked.base_color,
                   metallic_roughness=baked.metallic_roughness, normal=baked.normal,
                   metallic=baked.metallic, roughness=baked.roughness)
    assert (tmp / "py.glb").read_bytes() == (tmp / "cli.glb").read_bytes()
    # The height as a 16-bit PNG, as `limn bake --height` writes it.
    cli("bake", tmp / "cli.lot", tmp / "torus.obj", "--atlas", "--size", 128, "-o",
        tmp / "c.png", "--mesh-out", tmp / "uv.obj", "--height", tmp / "cli-h.png")
    limn.write_png(tmp / "py-h.png", baked.height)
    assert (tmp / "py-h.png").read_bytes() == (tmp / "cli-h.png").read_bytes()
    ihdr = (tmp / "py-h.png").read_bytes()[16:26]
    assert struct.unpack(">IIBB", ihdr) == (128, 128, 16, 0)


def test_batch_bakes_a_material_glb(tmp_path):
    limn.write_mesh(limn.shape("torus"), tmp_path / "torus.obj")
    (tmp_path / "m.json").write_text(json.dumps(SCRIPT))
    line = {"input": "torus.obj", "steps": [
        {"unwrap": {"size": 128}},
        {"paint": {"strokes": "m.json"}},
        {"bake": {"uv": True, "size": 128, "normal_map": True, "output": "torus.glb"}}]}
    (tmp_path / "assets.jsonl").write_text(json.dumps(line) + "\n")
    [asset] = batch.read_manifest(tmp_path / "assets.jsonl")
    result = batch.run_asset(asset)
    assert result["status"] == "done", result["error"]
    glb = (tmp_path / "torus.glb").read_bytes()
    length = struct.unpack("<I", glb[12:16])[0]
    gltf = json.loads(glb[20:20 + length])
    material = gltf["materials"][0]
    assert "metallicRoughnessTexture" in material["pbrMetallicRoughness"]
    assert "normalTexture" in material
    assert "TANGENT" in gltf["meshes"][0]["primitives"][0]["attributes"]
    # A normal map has no place in a PNG bake: refused, not dropped.
    line["steps"][2]["bake"]["output"] = "torus.png"
    (tmp_path / "assets.jsonl").write_text(json.dumps(line) + "\n")
    [asset] = batch.read_manifest(tmp_path / "assets.jsonl")
    result = batch.run_asset(asset, force=True)
    assert result["status"] == "failed" and "normal_map" in result["error"]
