# Type stubs of the tom package (the native module tom._tom).
from typing import Any, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

format_version: Tuple[int, int]

class Error(Exception): ...
class FormatError(Error): ...
class MeshError(Error): ...
MeshFileError = MeshError
class IoError(Error): ...
class ArgumentError(Error): ...
class ParseError(Error): ...

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

def open(path: str, byte_limit: Optional[int] = ...) -> File: ...
def open_bytes(data: Union[bytes, bytearray, memoryview, npt.NDArray[np.uint8]], name: str = ...) -> File: ...
def import_file(path: str) -> list[Mesh]: ...
def build(positions: Union[npt.ArrayLike, Mesh], triangles: Optional[npt.ArrayLike] = ..., normals: Optional[npt.ArrayLike] = ...,
          uv: Optional[npt.ArrayLike] = ..., *, name: str = ..., predicate: str = ..., strategy: str = ..., pair_threshold: float = ...,
          attribute_weight: float = ..., max_rotation_degrees: float = ..., threads: int = ..., foresight: bool = ...,
          lock_borders: bool = ..., animation_weight: float = ..., weld: bool = ..., keep_topology: bool = ...) -> BuiltMesh: ...
def serialize(meshes: Sequence[BuiltMesh], index_size: str = ...) -> bytes: ...
def write(path: str, meshes: Sequence[BuiltMesh], index_size: str = ...) -> None: ...
def report(original: Mesh, built: BuiltMesh, levels: Sequence[float] = ..., error_curve: bool = ...) -> dict[str, Any]: ...

class _Tcr:
    """tom.tcr: libtcr's runtime, frame governor, calibration file and simulated renderer."""
    class CostModel:
        t_init_ms: float
        t_final_ms: float
        t_setup_ms: float
        t_tri_ms: float
        t_vert_ms: float
        t_pix_ms: float
        safety_ms: float
        noise_rel: float
        flat_t_tri_ms: float
        flat_t_vert_ms: float
        flat_t_pix_ms: float
        textured_t_tri_ms: float
        textured_t_vert_ms: float
        textured_t_pix_ms: float
        imposter_t_setup_ms: float
        imposter_t_pix_ms: float
        refresh_t_setup_ms: float
        meshed_t_tri_ms: float
        meshed_refresh_t_setup_ms: float
    class Runtime:
        def __init__(self, model: "_Tcr.CostModel", selector: str = ...) -> None: ...
        def add_object(self, mesh: FileMesh, transform: npt.ArrayLike, weight: float = ...) -> int: ...
        def __len__(self) -> int: ...
        def plan_frame(self, view: npt.ArrayLike, projection: npt.ArrayLike, width: int, height: int,
                       budget_ms: float = ..., previous_frame_ms: float = ...) -> dict[str, Any]: ...
        def object(self, id: int) -> dict[str, Any]: ...
        def indices(self, id: int) -> Tuple[npt.NDArray[np.uint32], int]: ...
    class FrameGovernor:
        def __init__(self, runtime: "_Tcr.Runtime", model: "_Tcr.CostModel", budget_ms: float = ..., safety_sigma: float = ...,
                     follow_noise: bool = ...) -> None: ...
        def plan_frame(self, view: npt.ArrayLike, projection: npt.ArrayLike, width: int, height: int) -> dict[str, Any]: ...
        def frame_done(self, extract_ms: float, render_ms: float, frame_ms: float = ...) -> None: ...
        warming_up: bool
        planning_reserve_ms: float
        model: "_Tcr.CostModel"
    class SimulatedRenderer:
        def __init__(self, noise_rel: float, slowdown: float = ..., seed: int = ..., within_allowance: bool = ...) -> None: ...
        def frame_ms(self, report: dict[str, Any], model: "_Tcr.CostModel") -> float: ...
    @staticmethod
    def read_cost_model(path: str) -> "_Tcr.CostModel": ...
    @staticmethod
    def calibrate(renderer: Any, meshes: Sequence[FileMesh], path: str = ...) -> "_Tcr.CostModel": ...
    @staticmethod
    def look_at(eye: Sequence[float], target: Sequence[float], up: Sequence[float]) -> npt.NDArray[np.float32]: ...
    @staticmethod
    def perspective(fov_y: float, aspect: float, z_near: float, z_far: float) -> npt.NDArray[np.float32]: ...

tcr: _Tcr
