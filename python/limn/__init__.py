"""limn: adaptive subdivision, octree painting and shape approximation for surfaces.

Meshes are numpy arrays without copies (:class:`Mesh`); every job of the ``limn`` command line is
a function with keyword arguments named like the command's options, returning the command's
``--json`` report as a dict. Long calls release the GIL. Bad input raises :class:`InputError` (a
``ValueError``) with the command line's one-line message.

    import limn
    mesh = limn.read_mesh("scan.obj")
    result = limn.simplify(mesh, proxies=200)
    limn.write_mesh(result.mesh, "cage.obj")
"""

from __future__ import annotations

import dataclasses
import json
import os
import warnings
from typing import Any, Optional

import numpy as np

from ._limn import (InputError, Mesh, Painter, PatchHierarchy, PatchTable, RepairableError,
                    StencilTable, Texture, __version__, load_texture, patches, read_mesh,
                    read_png, shape, shape_names, udim_tiles)
from . import _limn

__all__ = [
    "InputError",
    "Mesh",
    "PaintResult",
    "Painter",
    "PatchHierarchy",
    "PatchTable",
    "RenderResult",
    "RepairResult",
    "RepairableError",
    "SimplifyResult",
    "StencilResult",
    "StencilTable",
    "SubdivideResult",
    "Texture",
    "UnwrapResult",
    "BakedMaterial",
    "__version__",
    "bake",
    "bake_material",
    "info",
    "load_texture",
    "paint",
    "patch_hierarchy",
    "patches",
    "read_mesh",
    "read_png",
    "render",
    "repair",
    "select_depths",
    "shape",
    "shape_names",
    "simplify",
    "stencils",
    "subdivide",
    "udim_tiles",
    "unwrap",
    "write_glb",
    "write_mesh",
    "write_png",
]


def write_mesh(mesh: Mesh, path: str | os.PathLike, *, format: Optional[str] = None,
               ascii: bool = False) -> list[str]:
    """Writes ``mesh`` to ``path`` atomically (a temporary file renamed into place).

    format: 'obj', 'ply', 'off', 'stl' or 'glb' (default: by extension). ascii: PLY as text.
    Returns the attributes the format cannot store (e.g. ``['uv']`` for STL); when there are
    any, a ``UserWarning`` names them too, as the command line warns on stderr.
    """
    dropped = _limn._write_mesh(mesh, os.fspath(path), format, ascii)
    if dropped:
        warnings.warn(f"{os.fspath(path)}: dropped {', '.join(dropped)} (not carried to this "
                      "output)", stacklevel=2)
    return dropped


def info(mesh: Mesh) -> dict[str, Any]:
    """``limn info --json``: counts, manifoldness, orientation, genus, valences, tags, bbox."""
    return _limn._info(mesh)


@dataclasses.dataclass
class RepairResult:
    """The repaired mesh, and ``stats``: the counts ``limn repair --json`` reports."""
    mesh: Mesh
    stats: dict[str, Any]


def repair(mesh: Mesh, *, weld_tolerance: float = 1e-6) -> RepairResult:
    """``limn repair``: weld, drop degenerate and duplicate faces, orient each piece (outward
    when closed), split non-manifold edges and vertices, drop unreferenced vertices.

    weld_tolerance: a fraction of the bounding-box diagonal (0: equal positions only). Every
    output vertex is an input vertex; UVs, normals, colours and tags follow.
    """
    out, stats = _limn._repair(mesh, float(weld_tolerance))
    return RepairResult(out, stats)


@dataclasses.dataclass
class SimplifyResult:
    """What :func:`simplify` made.

    mesh: the simplified mesh (its vertices are input vertices). labels: (faces,) uint32, the
    cluster of every input face. face_cluster: the cluster of every output face.
    vertex_source: the input vertex of every output vertex. stats: ``limn simplify --json``'s
    report (energy, clusters, counts, meshing and optimiser counters, timings).
    """
    mesh: Mesh
    labels: np.ndarray
    face_cluster: np.ndarray
    vertex_source: np.ndarray
    stats: dict[str, Any]


def simplify(mesh: Mesh, *, proxies: Optional[int] = None, target_error: Optional[float] = None,
             max_proxies: int = 0, method: str = "greedy", seeding: str = "curvature",
             seed: int = 1, no_fill: bool = False, iterations: int = 30, teleports: int = 16,
             split_threshold: float = 0.5, polygons: bool = False,
             distance: Optional[int | bool] = None) -> SimplifyResult:
    """``limn simplify``: variational shape approximation into a few feature-aligned polygons.

    proxies: K clusters (default 100, or 10 to start from with target_error). target_error: add
    clusters until E / surface area <= this (max_proxies caps K; 0: a third of the faces).
    method: 'greedy' (local greedy optimiser) or 'lloyd'. seeding: 'curvature' or 'random'
    (seed picks the seed faces). no_fill: keep the K curvature seeding reaches. iterations:
    Lloyd's cap. teleports: greedy's merge-and-split moves after convergence (0: as published).
    split_threshold: chain splitting in meshing. polygons: one polygon per cluster instead of
    triangles. distance: also measure Hausdorff and RMS distances with this many samples (True:
    200000). The input must be an edge-manifold, oriented mesh (see :func:`repair`).
    """
    if distance is True:
        distance = 200000
    elif distance is False:
        distance = None
    out, labels, face_cluster, vertex_source, stats = _limn._simplify(
        mesh, proxies, target_error, max_proxies, method, seeding, seed, no_fill, iterations,
        teleports, split_threshold, polygons, distance)
    return SimplifyResult(out, labels, face_cluster, vertex_source, stats)


@dataclasses.dataclass
class UnwrapResult:
    """What :func:`unwrap` made.

    mesh: the input with new UVs (``uvs``/``uv_indices``; v up, tile (u // 1, v // 1)).
    face_chart: (faces,) uint32, the chart of every face. chart_tile: (charts,) uint32, the tile of
    every chart (UDIM 1001 + index). stats: ``limn unwrap --json``'s report (charts, tiles,
    density, utilization, stretch, the independent check of the layout, timings).
    """
    mesh: Mesh
    face_chart: np.ndarray
    chart_tile: np.ndarray
    stats: dict[str, Any]


def unwrap(mesh: Mesh, *, max_stretch: float = 1.003, size: int = 1024,
           texels_per_unit: Optional[float] = None, tiles: int = 1,
           padding: int = 2) -> UnwrapResult:
    """``limn unwrap``: an automatic UV atlas. Charts are cut (VSA along the sharpest feature)
    until each one's conformal map has no flip and a Sander L2 stretch <= max_stretch, then
    packed with ``padding`` free texels around each into one ``size`` x ``size`` atlas, or into at
    most ``tiles`` UDIM tiles. texels_per_unit: the density (charts longer than a tile are cut);
    default: the densest that fits. The input must be an edge-manifold, oriented mesh (see
    :func:`repair`); any UVs it has are replaced.
    """
    out, face_chart, chart_tile, stats = _limn._unwrap(mesh, float(max_stretch), int(size),
                                                       texels_per_unit, int(tiles), int(padding))
    return UnwrapResult(out, face_chart, chart_tile, stats)


@dataclasses.dataclass
class SubdivideResult:
    """The subdivided mesh, and ``stats``: ``limn subdivide --json``'s per-level counts and
    timings."""
    mesh: Mesh
    stats: dict[str, Any]


def subdivide(mesh: Mesh, *, uniform: int, limit: bool = False) -> SubdivideResult:
    """``limn subdivide --uniform L [--limit]``: Catmull-Clark refinement of every face L times
    (0-8), with OpenSubdiv's rules for the cage's creases, corners, holes and boundary tags.

    limit: push the points to the limit surface, with limit normals (UVs refined as face-varying
    data and colours come along); without it only the last level is kept (the lean path).
    """
    out, stats = _limn._subdivide_uniform(mesh, int(uniform), bool(limit))
    return SubdivideResult(out, stats)


@dataclasses.dataclass
class StencilResult:
    """table: the cage's points to ``mesh``'s points in one pass (:class:`StencilTable`). mesh:
    the refined mesh (topology, and positions of the cage as it is)."""
    table: StencilTable
    mesh: Mesh


def stencils(mesh: Mesh, *, uniform: int, limit: bool = False) -> StencilResult:
    """Stencils for an animated cage: ``subdivide(mesh, uniform=L, limit=limit)`` once, and a
    table that turns any new cage positions (or colours, or any per-vertex data) into the refined
    mesh's, ``result.table.apply(new_positions)``, without refining again.
    """
    table, refined = _limn._stencils(mesh, int(uniform), bool(limit))
    return StencilResult(table, refined)


def _size(resolution) -> tuple[int, int]:
    if isinstance(resolution, str):
        try:
            width, height = (int(v) for v in resolution.lower().split("x"))
        except ValueError:
            raise InputError(f"resolution {resolution}: expected WxH") from None
        return width, height
    width, height = resolution
    return int(width), int(height)


def patch_hierarchy(mesh: Mesh, *, max_depth: int = 10) -> PatchHierarchy:
    """Every patch ``mesh`` can need down to ``max_depth`` (0-12), each vertex's errors measured
    on it (``limn subdivide --adaptive --tolerance PX --errors measured``). Then per view:
    ``depths = h.select_depths(camera=..., resolution=..., tolerance=0.5)`` and
    ``h.select(depths)``, a :class:`PatchTable` to evaluate or tessellate; nothing is refined
    again."""
    return _limn._patch_hierarchy(mesh, int(max_depth))


def _hierarchy_select_depths(self, *, camera=None, resolution=(1280, 720), tolerance=0.5,
                             previous=None):
    """A depth per cage vertex (uint8) that keeps the view's screen error under ``tolerance``
    pixels, from the measured errors. camera: (ex, ey, ez, tx, ty, tz, fovy_deg) or a report's
    dict (default: the cage framed). previous: the last view's depths (hysteresis: depths fall
    only when the need is well below, so small camera moves do not flicker)."""
    width, height = _size(resolution)
    return _limn.PatchHierarchy._select_depths(self, width, height, _camera_numbers(camera),
                                               float(tolerance), previous)


PatchHierarchy.select_depths = _hierarchy_select_depths


def _patch_table_render(self, *, resolution=(1280, 720), camera=None, background=(1.0, 1.0, 1.0),
                        samples: int = 4, wireframe: bool = False, depth_colors: bool = False,
                        tess: Optional[int] = None, tess_px: float = 8.0,
                        texture: Optional[Texture] = None, nearest: bool = False):
    """``limn render --adaptive``: the patches drawn on the GPU with tessellation shaders
    (headless; llvmpipe without a GPU) -> :class:`RenderResult`. tess: segments per patch edge
    (1-32; default: about one per ``tess_px`` pixels of projected edge). depth_colors: colour by
    refinement level. wireframe: patch outlines. Other options as :func:`render`."""
    width, height = _size(resolution)
    image, stats = self._render(width, height, int(samples), _background(background),
                                _camera_numbers(camera), wireframe, depth_colors,
                                int(tess or 0), float(tess_px), texture, nearest)
    return RenderResult(image, stats)


PatchTable.render = _patch_table_render


def select_depths(mesh: Mesh, *, camera=None, resolution=(1280, 720), tolerance: float = 0.5,
                  max_depth: int = 10) -> np.ndarray:
    """A depth per cage vertex (uint8) for a view from estimated errors (no hierarchy: cheaper,
    more conservative than :meth:`PatchHierarchy.select_depths`); feed it to
    ``patches(mesh, depth=max_depth, vertex_depth=...)``."""
    width, height = _size(resolution)
    return _limn._estimate_depths(mesh, width, height, _camera_numbers(camera), float(tolerance),
                                  int(max_depth))


@dataclasses.dataclass
class RenderResult:
    """image: (h, w, 4) uint8 RGBA, rows top to bottom. stats: ``limn render --json``'s report
    (renderer, camera, polygons drawn, triangles, GPU and CPU ms)."""
    image: np.ndarray
    stats: dict[str, Any]


def _background(background) -> list[float]:
    bg = [float(c) for c in background]
    if len(bg) == 3:
        bg.append(1.0)
    if len(bg) != 4 or not all(0.0 <= c <= 1.0 for c in bg):
        raise InputError(f"background {background}: three or four numbers 0-1")
    return bg


def _camera_numbers(camera) -> Optional[list[float]]:
    if camera is None:
        return None
    if isinstance(camera, dict):  # the form a report gives back
        return [*camera["eye"], *camera["target"], camera["fovy_deg"]]
    return [float(x) for x in camera]


def render(mesh: Mesh, *, resolution: tuple[int, int] | str = (1280, 720),
           camera=None, background=(1.0, 1.0, 1.0), samples: int = 4, flat: bool = False,
           wireframe: bool = False, uv_checker: float = 0.0, texture: Optional[Texture] = None,
           nearest: bool = False) -> RenderResult:
    """``limn render MESH``: the mesh drawn headless (EGL; Mesa's llvmpipe without a GPU).

    resolution: (width, height) or "WxH". camera: (ex, ey, ez, tx, ty, tz, fovy_deg) or a
    report's ``{"eye", "target", "fovy_deg"}`` (default: the whole mesh framed). background:
    RGB or RGBA in [0, 1]. samples: multisampling 1-16. flat: one normal per polygon.
    wireframe: polygon edges. uv_checker: the mesh's UVs as a checker of N squares per unit.
    texture: colour from a painted octree texture (nearest: nearest texel, not filtered).
    """
    width, height = _size(resolution)
    image, stats = _limn._render_mesh(mesh, int(width), int(height), int(samples),
                                      _background(background),
                                      _camera_numbers(camera), flat, wireframe, float(uv_checker),
                                      texture, nearest)
    return RenderResult(image, stats)


def write_png(path: str | os.PathLike, image: np.ndarray) -> None:
    """Writes an (h, w, 4) uint8 RGBA image as a PNG, atomically; an (h, w) uint16 image (a
    baked height) as a 16-bit greyscale PNG."""
    image = np.asarray(image)
    if image.ndim == 2 and image.dtype == np.uint16:
        _limn._write_png16(os.fspath(path), image)
    else:
        _limn._write_png(os.fspath(path), image)


@dataclasses.dataclass
class PaintResult:
    """The painted texture, and ``stats``: ``limn paint --json``'s report (strokes, dabs, samples
    changed, leaves and bricks created, picks, the texture's sizes, timings)."""
    texture: Texture
    stats: dict[str, Any]


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    return value


def _script_text(strokes) -> tuple[str, str]:
    if isinstance(strokes, os.PathLike) or (isinstance(strokes, str)
                                            and not strokes.lstrip().startswith(("{", "["))):
        name = os.fspath(strokes)
        with open(name, encoding="utf-8") as f:
            return name, f.read()
    if isinstance(strokes, str):
        return "strokes", strokes
    return "strokes", json.dumps(_jsonable(strokes))


def _painter_run(self, strokes) -> dict[str, Any]:
    """Paints a stroke script (a dict, its JSON text or a file, as :func:`paint` takes) into
    the session's texture; each stroke and fill can then be undone. Returns the counts
    (strokes, dabs, samples changed, undos and redos the script did)."""
    name, text = _script_text(strokes)
    return self._run(text, name)


Painter.run = _painter_run


def paint(mesh: Mesh, strokes, *, depth: int = 10, texture: Optional[Texture] = None,
          background=(0.0, 0.0, 0.0, 0.0), channel_defaults=(0.5, 0.0, 0.5),
          height_scale: Optional[float] = None) -> PaintResult:
    """``limn paint``: runs a stroke script on ``mesh`` into a new octree texture (or a copy of
    ``texture``, continued).

    strokes: the script as docs/paint-strokes.md describes it: a dict (``{"strokes": [...]}``,
    numpy arrays allowed for points), its JSON text, or the path of a JSON file. depth: the leaf
    level of entries that give none (1-16; 10 is 1024^3 over the mesh's bounding cube).
    background: RGB(A) in [0, 1] of unpainted surface in a new texture. Entries may paint
    material channels (``"roughness"``, ``"metallic"``, ``"height"``); channel_defaults:
    (roughness, metallic, height) where they are not painted, when first painted.
    height_scale: model units of height 1 (default: 2% of the texture's cube, or the texture's).
    """
    name, text = _script_text(strokes)
    bg = [float(c) for c in background]
    if len(bg) == 3:
        bg.append(1.0)
    if len(bg) != 4:
        raise InputError(f"background {background}: expected r,g,b[,a] in [0, 1]")
    defaults = [float(c) for c in channel_defaults]
    if len(defaults) != 3:
        raise InputError(f"channel_defaults {channel_defaults}: expected (roughness, metallic, "
                         "height) in [0, 1]")
    out, stats = _limn._paint(mesh, text, name, int(depth), bg, texture, defaults,
                              None if height_scale is None else float(height_scale))
    return PaintResult(out, stats)


def bake(texture: Texture, mesh: Mesh, *, uv: bool = False, size: int = 1024,
         resolution: Optional[tuple[int, int]] = None, gutter: int = 8,
         nearest: bool = False, udim: int = 1001) -> np.ndarray:
    """``limn bake``: the texture as RGBA per vertex ((n, 4) float32, the lookup at each vertex
    along its normal), or with ``uv=True`` into the mesh's UV layout as an (h, w, 4) uint8 image
    (``size`` square or ``resolution`` (w, h); ``gutter`` pixels of dilation around charts) of
    UDIM tile ``udim`` (see :func:`udim_tiles`; :func:`unwrap` makes an atlas).
    nearest: nearest texels instead of the filtered colour the renderer shows. InputError when
    the texture was painted on another mesh (under half of the vertices fall in its cells).
    """
    if not uv:
        return _limn._bake_vertex_colors(texture, mesh, nearest)
    width, height = resolution if resolution is not None else (size, size)
    return _limn._bake_uv_image(texture, mesh, int(width), int(height), int(gutter), nearest,
                                int(udim), False)["base_color"]


@dataclasses.dataclass
class BakedMaterial:
    """A material baked into one UV tile (:func:`bake_material`). Images are numpy arrays, rows
    top to bottom; None where the texture has nothing to bake. ``metallic`` and ``roughness`` are
    the factors a glTF material multiplies the metallic-roughness texture by (1 with the
    texture; the channel defaults without one)."""
    base_color: np.ndarray                      # (h, w, 4) uint8, sRGB
    metallic_roughness: Optional[np.ndarray]    # (h, w, 4) uint8: G roughness, B metalness
    height: Optional[np.ndarray]                # (h, w) uint16
    normal: Optional[np.ndarray]                # (h, w, 4) uint8, tangent space, +Y along +v
    metallic: float
    roughness: float


def bake_material(texture: Texture, mesh: Mesh, *, size: int = 1024,
                  resolution: Optional[tuple[int, int]] = None, gutter: int = 8,
                  nearest: bool = False, udim: int = 1001,
                  normal_map: bool = False) -> BakedMaterial:
    """``limn bake`` of every material channel into the mesh's UVs (as :func:`bake` with
    ``uv=True``): base colour; roughness and metalness packed as glTF wants them and height as
    16 bits, when the texture has channels; with ``normal_map`` a tangent-space normal map of
    the height (height_scale model units per unit). Write them with :func:`write_png` and
    :func:`write_glb`."""
    width, height = resolution if resolution is not None else (size, size)
    images = _limn._bake_uv_image(texture, mesh, int(width), int(height), int(gutter), nearest,
                                  int(udim), bool(normal_map))
    if images["metallic_roughness"] is not None:
        metallic = roughness = 1.0
    else:
        roughness, metallic, _ = texture.channel_defaults
    return BakedMaterial(images["base_color"], images["metallic_roughness"], images["height"],
                         images["normal"], float(metallic), float(roughness))


def write_glb(mesh: Mesh, path: str | os.PathLike, *, base_color: Optional[np.ndarray] = None,
              metallic_roughness: Optional[np.ndarray] = None,
              normal: Optional[np.ndarray] = None, metallic: float = 0.0,
              roughness: float = 1.0) -> None:
    """Writes ``mesh`` as a GLB, atomically, with a pbrMetallicRoughness material: ``base_color``
    an (h, w, 4) uint8 image (sRGB, e.g. from :func:`bake` with ``uv=True``),
    ``metallic_roughness`` (G roughness, B metalness) and ``normal`` (the material's
    normalTexture), each embedded as a PNG and mapped by the mesh's UVs (TEXCOORD_0);
    ``metallic`` and ``roughness`` its factors. As ``limn bake TEXTURE MESH -o asset.glb``; a
    :class:`BakedMaterial` gives all of them.
    """
    _limn._write_glb(mesh, os.fspath(path), base_color, metallic_roughness, normal,
                     float(metallic), float(roughness))
