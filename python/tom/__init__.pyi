# Type stubs of the tom package (the native module tom._tom).
from typing import Any, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

format_version: Tuple[int, int]

class Error(Exception): ...
class FormatError(Error): ...
class MeshFileError(Error): ...
class IoError(Error): ...
class ArgumentError(Error): ...

class _MeshView:
    name: str
    vertex_count: int
    triangle_count: int
    min_vertex_count: int
    usable_floor: int
    material: int
    positions: npt.NDArray[np.float32]
    normals: Optional[npt.NDArray[np.float32]]
    uv: Optional[npt.NDArray[np.float32]]
    colors: Optional[npt.NDArray[np.float32]]
    triangles: Union[npt.NDArray[np.uint16], npt.NDArray[np.uint32]]
    substitute: Union[npt.NDArray[np.uint16], npt.NDArray[np.uint32]]
    carried_streams: dict[str, npt.NDArray[Any]]
    def vertex_count_for(self, fraction: Optional[float] = ..., triangles: Optional[int] = ..., below_floor: bool = ...) -> int: ...
    def active_triangles(self, vertices: int) -> int: ...
    parts: List[Tuple[int, int, int]]
    def draws(self, *, fraction: Optional[float] = ..., vertices: Optional[int] = ..., triangles: Optional[int] = ...) -> List[Tuple[int, int, int]]: ...
    def extract(self, *, fraction: Optional[float] = ..., vertices: Optional[int] = ..., triangles: Optional[int] = ...,
                out: Optional[npt.NDArray[Any]] = ...) -> Tuple[npt.NDArray[Any], int]: ...

class FileMesh(_MeshView): ...
class BuiltMesh(_MeshView): ...

class File:
    path: str
    provenance: str | None
    meshes: list[FileMesh]
    materials: list[dict[str, Any]]
    images: list[dict[str, Any]]
    instances: list[dict[str, Any]]
    def __len__(self) -> int: ...

class Mesh:
    name: str
    vertex_count: int
    triangle_count: int
    positions: npt.NDArray[np.float32]
    normals: Optional[npt.NDArray[np.float32]]
    uv: Optional[npt.NDArray[np.float32]]
    triangles: npt.NDArray[np.uint32]
    def __init__(self, positions: npt.ArrayLike, triangles: npt.ArrayLike, normals: Optional[npt.ArrayLike] = ...,
                 uv: Optional[npt.ArrayLike] = ..., name: str = ...) -> None: ...

def open(path: str) -> File: ...
def open_bytes(data: Union[bytes, bytearray, memoryview, npt.NDArray[np.uint8]], name: str = ...) -> File: ...
def import_file(path: str) -> list[Mesh]: ...
def build(positions: Union[npt.ArrayLike, Mesh], triangles: Optional[npt.ArrayLike] = ..., normals: Optional[npt.ArrayLike] = ...,
          uv: Optional[npt.ArrayLike] = ..., *, name: str = ..., predicate: str = ..., strategy: str = ..., pair_threshold: float = ...,
          attribute_weight: float = ..., max_rotation_degrees: float = ..., threads: int = ..., foresight: bool = ...,
          lock_borders: bool = ..., animation_weight: float = ..., weld: bool = ...) -> BuiltMesh: ...
def serialize(meshes: Sequence[BuiltMesh], index_size: str = ...) -> bytes: ...
def write(path: str, meshes: Sequence[BuiltMesh], index_size: str = ...) -> None: ...
def report(original: Mesh, built: BuiltMesh, levels: Sequence[float] = ..., error_curve: bool = ...) -> dict[str, Any]: ...
