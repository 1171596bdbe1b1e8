"""limn.Mesh and mesh files: views without copies, checked input, the CLI's files byte for byte."""

import threading
import warnings

import numpy as np
import pytest

import limn


def quad_mesh():
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], np.float32)
    return limn.Mesh.from_arrays(positions, [[0, 1, 2, 3], [1, 4, 2]])


def test_arrays_are_views_of_the_mesh():
    mesh = limn.shape("torus")
    p = mesh.positions
    assert p.dtype == np.float32 and p.shape == (mesh.vertex_count, 3)
    assert not p.flags.owndata and p.base is not None
    # Two views share the mesh's memory, and an edit through one is the mesh's.
    assert np.shares_memory(p, mesh.positions)
    p[0] = (7, 8, 9)
    assert tuple(mesh.positions[0]) == (7, 8, 9)
    faces = mesh.faces
    assert faces.shape == (mesh.face_count, 4) and faces.dtype == np.uint32
    assert np.shares_memory(faces, mesh.face_vertices)
    # A view keeps its mesh alive.
    del mesh
    assert p[0, 0] == 7


def test_views_survive_the_mesh_in_another_thread():
    views = []
    thread = threading.Thread(target=lambda: views.append(limn.shape("cube").positions))
    thread.start()
    thread.join()
    assert views[0].shape == (8, 3)


def test_from_arrays_layouts_agree():
    a = quad_mesh()
    b = limn.Mesh.from_arrays(a.positions.copy(), a.face_vertices.copy(),
                              offsets=a.face_offsets.copy())
    assert np.array_equal(a.face_offsets, [0, 4, 7])
    assert np.array_equal(a.face_vertices, b.face_vertices)
    assert np.array_equal(a.face_offsets, b.face_offsets)
    with pytest.raises(limn.InputError, match="mixes face sizes"):
        a.faces  # noqa: B018
    # float64 and lists are converted (copied) to float32.
    c = limn.Mesh.from_arrays(a.positions.astype(np.float64).tolist(), [[0, 1, 2, 3], [1, 4, 2]])
    assert np.array_equal(c.positions, a.positions)


def test_bad_arrays_raise_clear_errors():
    p = np.zeros((3, 3), np.float32)
    p[1, 0] = p[2, 1] = 1
    with pytest.raises(limn.InputError, match="references vertex 5"):
        limn.Mesh.from_arrays(p, [[0, 1, 5]])
    with pytest.raises(limn.InputError, match="out of range"):
        limn.Mesh.from_arrays(p, [[0, 1, -1]])
    with pytest.raises(limn.InputError, match=r"expected shape \(n, 3\)"):
        limn.Mesh.from_arrays(p[:, :2], [[0, 1, 2]])
    bad = p.copy()
    bad[2, 2] = np.nan
    with pytest.raises(limn.InputError, match="not finite"):
        limn.Mesh.from_arrays(bad, [[0, 1, 2]])
    with pytest.raises(TypeError, match="integers"):
        limn.Mesh.from_arrays(p, np.array([[0, 1, 2.0]]))
    with pytest.raises(TypeError, match="numbers"):
        limn.Mesh.from_arrays(np.array([["a", "b", "c"]] * 3), [[0, 1, 2]])
    with pytest.raises(limn.RepairableError, match="repeats vertex"):
        limn.Mesh.from_arrays(p, [[0, 1, 1]])
    assert issubclass(limn.InputError, ValueError)
    assert issubclass(limn.RepairableError, limn.InputError)


def test_assigning_an_array_is_checked_and_atomic():
    mesh = quad_mesh()
    mesh.colors = np.tile([1.0, 0.5, 0.25, 1.0], (5, 1))
    assert mesh.colors.shape == (5, 4)
    before = mesh.face_vertices.copy()
    with pytest.raises(limn.InputError):
        mesh.face_vertices = np.array([0, 1, 2, 9, 1, 4, 2])
    assert np.array_equal(mesh.face_vertices, before)  # left as it was
    with pytest.raises(limn.InputError):
        mesh.positions = np.zeros((2, 3))  # faces would reference missing vertices
    assert mesh.vertex_count == 5


def test_files_are_the_cli_files(tmp_path, models, cli):
    src = models / "tri" / "spot.obj"
    mesh = limn.read_mesh(src)
    info = limn.info(mesh)
    expected = cli("info", src, json_out=True)
    assert info == {k: v for k, v in expected.items() if k not in ("file", "timings_ms")}
    for ext in ("obj", "ply", "off", "glb"):
        ours, theirs = tmp_path / f"py.{ext}", tmp_path / f"cli.{ext}"
        with warnings.catch_warnings(record=True):
            limn.write_mesh(mesh, ours)
        cli("convert", src, theirs)
        assert ours.read_bytes() == theirs.read_bytes(), ext
        if ext in ("ply", "glb"):
            continue  # per-vertex UVs: split at UV seams
        again = limn.read_mesh(ours)
        assert np.array_equal(again.positions, mesh.positions)
        assert np.array_equal(again.face_vertices, mesh.face_vertices)


def test_dropped_attributes_warn(tmp_path, models):
    mesh = limn.read_mesh(models / "tri" / "spot.obj")
    assert mesh.uv_indices.size
    with pytest.warns(UserWarning, match="dropped uv"):
        dropped = limn.write_mesh(mesh, tmp_path / "spot.stl")
    assert dropped == ["uv"]


def test_bad_files_raise_the_cli_message(tmp_path, cli):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    with pytest.raises(limn.InputError) as error:
        limn.read_mesh(bad)
    done = cli("info", bad, check=False)
    assert done.returncode == 2
    assert str(error.value) in done.stderr
    with pytest.raises(limn.InputError, match="cannot tell the output format"):
        limn.write_mesh(quad_mesh(), tmp_path / "out.xyz")
    assert not (tmp_path / "out.xyz").exists()
    with pytest.raises(limn.InputError, match="unknown shape"):
        limn.shape("teapot")


def test_the_stub_names_what_the_module_has():
    import ast
    import pathlib

    from limn import _limn

    stub = pathlib.Path(_limn.__file__).with_name("_limn.pyi")
    tree = ast.parse(stub.read_text())
    declared = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    declared |= {n.target.id for n in tree.body if isinstance(n, ast.AnnAssign)}
    present = {n for n in dir(_limn) if not n.startswith("__") or n == "__version__"}
    assert declared == present
    mesh_stub = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Mesh")
    members = {n.name for n in mesh_stub.body if isinstance(n, ast.FunctionDef)}
    members |= {n.target.id for n in mesh_stub.body if isinstance(n, ast.AnnAssign)}
    assert members == {n for n in dir(limn.Mesh) if not n.startswith("_")} | {"__init__"}


def test_every_public_name_has_a_docstring():
    missing = []
    for name in limn.__all__:
        obj = getattr(limn, name)
        if not (obj.__doc__ or "").strip():
            missing.append(name)
        if isinstance(obj, type):
            for member, value in vars(obj).items():
                doc = (getattr(value, "__doc__", None) or "").strip()
                if not member.startswith("_") and (not doc or doc.startswith("(self")):
                    missing.append(f"{name}.{member}")
    assert not missing
