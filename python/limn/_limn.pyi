# Types of the compiled core, for editors and type checkers (the package's own functions are in
# __init__.py with their annotations).
import os
from typing import Any, Optional, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

class InputError(ValueError): ...
class RepairableError(InputError): ...

class Mesh:
    """A polygon mesh as flat arrays; every array property is a view of the mesh's memory."""
    def __init__(self) -> None: ...
    @staticmethod
    def from_arrays(
        positions: npt.ArrayLike,
        faces: npt.ArrayLike | Sequence[Sequence[int]],
        *,
        offsets: Optional[npt.ArrayLike] = None,
        uvs: Optional[npt.ArrayLike] = None,
        uv_indices: Optional[npt.ArrayLike] = None,
        normals: Optional[npt.ArrayLike] = None,
        normal_indices: Optional[npt.ArrayLike] = None,
        colors: Optional[npt.ArrayLike] = None,
        crease_edges: Optional[npt.ArrayLike] = None,
        crease_sharpness: Optional[npt.ArrayLike] = None,
        corner_vertices: Optional[npt.ArrayLike] = None,
        corner_sharpness: Optional[npt.ArrayLike] = None,
        hole_faces: Optional[npt.ArrayLike] = None,
    ) -> Mesh: ...
    @property
    def vertex_count(self) -> int: ...
    @property
    def face_count(self) -> int: ...
    @property
    def corner_count(self) -> int: ...
    @property
    def faces(self) -> npt.NDArray[np.uint32]: ...
    positions: npt.NDArray[np.float32]
    normals: npt.NDArray[np.float32]
    uvs: npt.NDArray[np.float32]
    colors: npt.NDArray[np.float32]
    crease_sharpness: npt.NDArray[np.float32]
    corner_sharpness: npt.NDArray[np.float32]
    face_offsets: npt.NDArray[np.uint32]
    face_vertices: npt.NDArray[np.uint32]
    normal_indices: npt.NDArray[np.uint32]
    uv_indices: npt.NDArray[np.uint32]
    crease_edges: npt.NDArray[np.uint32]
    corner_vertices: npt.NDArray[np.uint32]
    hole_faces: npt.NDArray[np.uint32]
    def copy(self) -> Mesh: ...

def read_mesh(path: str | os.PathLike[str], *, format: Optional[str] = None, weld: bool = False,
              soup: bool = False) -> Mesh: ...
def shape(name: str, *, seed: int = 1) -> Mesh: ...
def shape_names() -> list[str]: ...
def _write_mesh(mesh: Mesh, path: str, format: Optional[str] = None,
                ascii: bool = False) -> list[str]: ...
def _info(mesh: Mesh) -> dict[str, Any]: ...
def _repair(mesh: Mesh, weld_tolerance: float) -> tuple[Mesh, dict[str, Any]]: ...
def _simplify(mesh: Mesh, proxies: Optional[int], target_error: Optional[float],
              max_proxies: int, method: str, seeding: str, seed: int, no_fill: bool,
              iterations: int, teleports: int, split_threshold: float, polygons: bool,
              distance: Optional[int]) -> tuple[Mesh, npt.NDArray[np.uint32],
                                               npt.NDArray[np.uint32], npt.NDArray[np.uint32],
                                               dict[str, Any]]: ...
def _subdivide_uniform(cage: Mesh, level: int, limit: bool) -> tuple[Mesh, dict[str, Any]]: ...
def read_png(path: str | os.PathLike[str]) -> npt.NDArray[np.uint8]: ...
def _write_png(path: str | os.PathLike[str], image: npt.ArrayLike) -> None: ...
def _render_mesh(mesh: Mesh, width: int, height: int, samples: int, background: Sequence[float],
                 camera: Optional[Sequence[float]], flat: bool, wireframe: bool,
                 uv_checker: float) -> tuple[npt.NDArray[np.uint8], dict[str, Any]]: ...
