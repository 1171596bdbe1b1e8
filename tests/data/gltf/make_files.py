#!/usr/bin/env python3
"""Writes the glTF and STL test files (tests/data/gltf/, tests/data/bad/, fuzz/corpus/{gltf,stl}/).

They are made here, byte by byte, rather than by limn's own writer, so that the readers are
tested against files that another program wrote: interleaved and padded strides, ubyte and
ushort indices, normalized integer UVs and colours, node transforms, strips and fans, external
and embedded buffers, and the broken variants in tests/data/bad/. Run from anywhere; the output
is deterministic.
"""
import base64
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
BAD = os.path.join(ROOT, "tests", "data", "bad")
CORPUS = os.path.join(ROOT, "fuzz", "corpus")

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125


class Gltf:
    """A one-buffer glTF document under construction."""

    def __init__(self):
        self.bin = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "limn tests/data/gltf/make_files.py"},
                    "buffers": [], "bufferViews": [], "accessors": [], "meshes": []}

    def view(self, data, stride=None, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride:
            v["byteStride"] = stride
        if target:
            v["target"] = target
        self.bin += data
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, view, comp, type_, count, offset=0, normalized=False, **extra):
        a = {"bufferView": view, "componentType": comp, "type": type_, "count": count}
        if offset:
            a["byteOffset"] = offset
        if normalized:
            a["normalized"] = True
        a.update(extra)
        self.doc["accessors"].append(a)
        return len(self.doc["accessors"]) - 1

    def floats(self, values, type_, width):
        """A tightly packed float accessor (positions get min/max)."""
        v = self.view(struct.pack("<%df" % len(values), *values), target=34962)
        extra = {}
        if type_ == "VEC3" and width == 3 and all(math.isfinite(x) for x in values):
            extra = {"min": [min(values[k::3]) for k in range(3)],
                     "max": [max(values[k::3]) for k in range(3)]}
        return self.accessor(v, FLOAT, type_, len(values) // width, **extra)

    def indices(self, values, comp=USHORT):
        fmt = {UBYTE: "B", USHORT: "H", UINT: "I"}[comp]
        v = self.view(struct.pack("<%d%s" % (len(values), fmt), *values), target=34963)
        return self.accessor(v, comp, "SCALAR", len(values))

    def mesh(self, primitives):
        self.doc["meshes"].append({"primitives": primitives})
        return len(self.doc["meshes"]) - 1

    def scene(self, nodes, roots):
        self.doc["nodes"] = nodes
        self.doc["scenes"] = [{"nodes": roots}]
        self.doc["scene"] = 0

    def json_text(self, uri=None):
        doc = json.loads(json.dumps(self.doc))
        if uri is None:
            uri = "data:application/octet-stream;base64," + base64.b64encode(self.bin).decode()
        doc["buffers"] = [{"byteLength": len(self.bin), "uri": uri}]
        return json.dumps(doc, indent=1) + "\n"

    def glb(self):
        doc = json.loads(json.dumps(self.doc))
        doc["buffers"] = [{"byteLength": len(self.bin)}]
        j = json.dumps(doc).encode()
        j += b" " * (-len(j) % 4)
        b = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
        total = 12 + 8 + len(j) + 8 + len(b)
        return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(j), b"JSON") + j
                + struct.pack("<I4s", len(b), b"BIN\0") + b)


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    mode = "wb" if isinstance(data, (bytes, bytearray)) else "w"
    with open(path, mode) as f:
        f.write(data)


def one_node(g, mesh):
    g.scene([{"mesh": mesh}], [0])


def quad():
    """A unit quad as two triangles: positions and normals interleaved (stride 24), float UVs."""
    g = Gltf()
    pos = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    inter = b"".join(struct.pack("<6f", *p, 0, 0, 1) for p in pos)
    v = g.view(inter, stride=24, target=34962)
    pa = g.accessor(v, FLOAT, "VEC3", 4, min=[0, 0, 0], max=[1, 1, 0])
    na = g.accessor(v, FLOAT, "VEC3", 4, offset=12)
    # glTF's v runs down the image: limn's (u, v) = (x, y) is stored as (x, 1 - y).
    ua = g.floats([0, 1, 1, 1, 1, 0, 0, 0], "VEC2", 2)
    ia = g.indices([0, 1, 2, 0, 2, 3])
    m = g.mesh([{"attributes": {"POSITION": pa, "NORMAL": na, "TEXCOORD_0": ua}, "indices": ia}])
    one_node(g, m)
    return g


def scene_trs():
    """One triangle placed three times: a parent translation over a child T*R*S, a mirroring
    matrix node, and a node outside the scene (never read)."""
    g = Gltf()
    pa = g.floats([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3", 3)
    na = g.floats([0, 0, 1] * 3, "VEC3", 3)
    m = g.mesh([{"attributes": {"POSITION": pa, "NORMAL": na}}])
    s = math.sqrt(0.5)
    nodes = [
        {"translation": [10, 0, 0], "children": [1]},
        {"translation": [0, 2, 0], "rotation": [0, 0, s, s], "scale": [2, 2, 2], "mesh": m},
        {"matrix": [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1], "mesh": m},
        {"translation": [100, 100, 100], "mesh": m},
    ]
    g.scene(nodes, [0, 2])
    return g


def strip_fan():
    """A TRIANGLE_STRIP without indices and a TRIANGLE_FAN with ubyte indices, in one mesh."""
    g = Gltf()
    sp = g.floats([0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 2, 0], "VEC3", 3)
    fp = g.floats([5, 0, 0, 6, 0, 0, 6, 1, 0, 5, 1, 0], "VEC3", 3)
    fi = g.indices([0, 1, 2, 3], UBYTE)
    m = g.mesh([{"attributes": {"POSITION": sp}, "mode": 5},
                {"attributes": {"POSITION": fp}, "indices": fi, "mode": 6}])
    one_node(g, m)
    return g


def colors():
    """Normalized integer attributes: ubyte UVs (stride 4) and ubyte RGBA in one primitive,
    ushort UVs and float RGB in another."""
    g = Gltf()
    pa = g.floats([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3", 3)
    uv8 = g.view(bytes([0, 255, 0, 0, 255, 255, 0, 0, 0, 0, 0, 0]), stride=4, target=34962)
    ua = g.accessor(uv8, UBYTE, "VEC2", 3, normalized=True)
    rgba = g.view(bytes([255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0]), target=34962)
    ca = g.accessor(rgba, UBYTE, "VEC4", 3, normalized=True)
    pb = g.floats([2, 0, 0, 3, 0, 0, 2, 1, 0], "VEC3", 3)
    uv16 = g.view(struct.pack("<6H", 0, 65535, 65535, 65535, 0, 0), target=34962)
    ub = g.accessor(uv16, USHORT, "VEC2", 3, normalized=True)
    cb = g.floats([0.25, 0.5, 0.75] * 3, "VEC3", 3)
    m = g.mesh([{"attributes": {"POSITION": pa, "TEXCOORD_0": ua, "COLOR_0": ca}},
                {"attributes": {"POSITION": pb, "TEXCOORD_0": ub, "COLOR_0": cb}}])
    one_node(g, m)
    return g


# Each side of the cube: outward normal, its 4 corners counter-clockwise seen from outside, and
# the (column, row) of its cell in a 4 x 3 cross-shaped unwrap; corner k gets the cell corner k.
CUBE_SIDES = [
    ((0, 0, 1), [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)], (1, 1)),
    ((1, 0, 0), [(1, -1, 1), (1, -1, -1), (1, 1, -1), (1, 1, 1)], (2, 1)),
    ((0, 0, -1), [(1, -1, -1), (-1, -1, -1), (-1, 1, -1), (1, 1, -1)], (3, 1)),
    ((-1, 0, 0), [(-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1)], (0, 1)),
    ((0, 1, 0), [(-1, 1, 1), (1, 1, 1), (1, 1, -1), (-1, 1, -1)], (1, 2)),
    ((0, -1, 0), [(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)], (1, 0)),
]


def seamed_cube():
    """A unit cube as most exporters write it: 24 vertices (4 per side, each with the side's
    normal and its own UVs from a cross-shaped unwrap), 12 triangles with uint indices."""
    g = Gltf()
    pos, nrm, uv, idx = [], [], [], []
    for n, corners, (cu, cv) in CUBE_SIDES:
        base = len(pos) // 3
        for k, c in enumerate(corners):
            pos += [0.5 * x for x in c]
            nrm += list(n)
            du, dv = [(0, 0), (1, 0), (1, 1), (0, 1)][k]
            u, v = (cu + du) / 4, (cv + dv) / 3
            uv += [u, 1 - v]
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    pa = g.floats(pos, "VEC3", 3)
    na = g.floats(nrm, "VEC3", 3)
    ua = g.floats(uv, "VEC2", 2)
    ia = g.indices(idx, UINT)
    m = g.mesh([{"attributes": {"POSITION": pa, "NORMAL": na, "TEXCOORD_0": ua}, "indices": ia}])
    one_node(g, m)
    return g


def triangle(positions=(0, 0, 0, 1, 0, 0, 0, 1, 0), **prim):
    g = Gltf()
    pa = g.floats(list(positions), "VEC3", 3)
    p = {"attributes": {"POSITION": pa}}
    p.update(prim)
    one_node(g, g.mesh([p]))
    return g


def bad_gltf():
    out = {}
    g = triangle()
    out["bad_missing_buffer.gltf"] = g.json_text(uri="no_such_buffer.bin")
    g = triangle()
    g.doc["accessors"][0]["count"] = 4  # 48 bytes from a 36-byte bufferView
    out["bad_accessor_past_view.gltf"] = g.json_text()
    g = triangle()
    g.doc["bufferViews"][0]["byteLength"] = 400  # the view runs past its 36-byte buffer
    out["bad_view_past_buffer.gltf"] = g.json_text()
    g = triangle()
    g.doc["meshes"][0]["primitives"][0]["indices"] = g.indices([0, 1, 7])
    out["bad_index_past_count.gltf"] = g.json_text()
    g = triangle()
    g.doc["accessors"][0]["type"] = "VEC2"
    g.doc["accessors"][0]["count"] = 4
    del g.doc["accessors"][0]["min"], g.doc["accessors"][0]["max"]
    out["bad_position_type.gltf"] = g.json_text()
    out["bad_points_mode.gltf"] = triangle(mode=0).json_text()
    out["bad_nan_position.gltf"] = triangle([0, 0, 0, float("nan"), 0, 0, 0, 1, 0]).json_text()
    g = triangle()
    g.doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = g.floats([0, 0, 1] * 2, "VEC3",
                                                                           3)
    out["bad_attribute_count.gltf"] = g.json_text()
    g = triangle()
    g.doc["nodes"] = [{"children": [1]}, {"children": [0], "mesh": 0}]
    out["bad_node_cycle.gltf"] = g.json_text()
    glb = quad().glb()
    out["bad_truncated.glb"] = glb[: len(glb) - 40]
    return out


def stl_binary(tris, header=b"binary STL from make_files.py", count=None):
    h = header + b"\0" * (80 - len(header))
    body = b"".join(struct.pack("<12fH", 0, 0, 0, *[x for v in t for x in v], 0) for t in tris)
    return h + struct.pack("<I", len(tris) if count is None else count) + body


def stl_ascii(tris, name="cube"):
    s = "solid %s\n" % name
    for t in tris:
        s += " facet normal 0 0 0\n  outer loop\n"
        for v in t:
            s += "   vertex %r %r %r\n" % v
        s += "  endloop\n endfacet\n"
    return s + "endsolid %s\n" % name


def cube_triangles():
    """The unit cube's 12 triangles, outward facing (the sides of seamed_cube)."""
    tris = []
    for _, corners, _ in CUBE_SIDES:
        c = [tuple(0.5 * x for x in p) for p in corners]
        tris += [(c[0], c[1], c[2]), (c[0], c[2], c[3])]
    return tris


def main():
    write(os.path.join(HERE, "quad.gltf"), quad().json_text())
    write(os.path.join(HERE, "scene_trs.gltf"), scene_trs().json_text())
    write(os.path.join(HERE, "strip_fan.gltf"), strip_fan().json_text())
    write(os.path.join(HERE, "colors.gltf"), colors().json_text())
    write(os.path.join(HERE, "cube_seams.gltf"), seamed_cube().json_text())
    g = quad()
    write(os.path.join(HERE, "external.gltf"), g.json_text(uri="external.bin"))
    write(os.path.join(HERE, "external.bin"), bytes(g.bin))
    for name, data in bad_gltf().items():
        write(os.path.join(BAD, name), data)

    tris = cube_triangles()
    write(os.path.join(BAD, "bad_truncated.stl"),
          stl_binary(tris, header=b"solid but binary, cut short")[:84 + 50 * 5 + 20])
    write(os.path.join(BAD, "bad_lying_count.stl"), stl_binary(tris[:2], count=1000000))
    bad = stl_ascii(tris[:2]).replace("vertex 0.5 -0.5 0.5", "vertex nan -0.5 0.5", 1)
    write(os.path.join(BAD, "bad_nan.stl"), bad)
    write(os.path.join(BAD, "bad_garbage.stl"), "this is not an STL file\n")
    two = stl_ascii(tris[:2])
    cut = two.index("   vertex", two.index("   vertex") + 1)
    cut = two.index("   vertex", cut + 1)
    write(os.path.join(BAD, "bad_facet_two_vertices.stl"),
          two[:cut] + two[two.index("  endloop"):])
    write(os.path.join(BAD, "bad_inf_binary.stl"),
          stl_binary([((0, 0, 0), (float("inf"), 0, 0), (0, 1, 0))]))

    write(os.path.join(CORPUS, "stl", "cube_ascii.stl"), stl_ascii(tris))
    write(os.path.join(CORPUS, "stl", "cube_binary.stl"), stl_binary(tris))
    write(os.path.join(CORPUS, "stl", "cube_solid_header.stl"),
          stl_binary(tris, header=b"solid cube (binary despite the name)"))
    write(os.path.join(CORPUS, "gltf", "quad.gltf"), quad().json_text())
    write(os.path.join(CORPUS, "gltf", "quad.glb"), quad().glb())
    write(os.path.join(CORPUS, "gltf", "strip_fan.glb"), strip_fan().glb())
    write(os.path.join(CORPUS, "gltf", "colors.glb"), colors().glb())
    write(os.path.join(CORPUS, "gltf", "scene_trs.glb"), scene_trs().glb())


if __name__ == "__main__":
    main()
