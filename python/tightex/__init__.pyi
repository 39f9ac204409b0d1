from typing import Any, Callable, Literal, Optional, Sequence, Union
from os import PathLike

import numpy as np
import numpy.typing as npt

ProgressCallback = Callable[[str, float], Optional[bool]]
Path = Union[str, PathLike]

class Error(Exception): ...
class InputError(Error): ...
class InternalError(Error): ...
class Cancelled(Error): ...

__version__: str
FIELDS: tuple[str, ...]

class Options:
    size: int = 0
    texels: float = 0.0
    aspect: float = 0.0
    allow_large_textures: bool = False
    allow_outside_files: bool = False
    layout: Literal["atlas", "per-component"] = "atlas"
    max_page_side: int = 8192
    max_piece_faces: int = 6000000
    holes: Literal["fill", "cut"] = "fill"
    map: Literal["detail", "area", "texel", "harmonic"] = "detail"
    balance: float = 1.0
    corners: Literal["arcs", "turning"] = "arcs"
    fit: bool = True
    fine_fit: bool = False
    material_map_budget_db: float = 51.0
    keep_untextured: bool = True
    measure: bool = True
    max_memory_mib: float = 0.0
    model_format: Optional[Literal["obj", "ply", "gltf", "glb"]] = None
    texture_format: Optional[Literal["png", "jpg", "webp"]] = None
    png_level: Optional[int] = None
    jpeg_quality: Optional[int] = None
    webp_quality: Optional[int] = None
    webp_lossless: bool = False
    target_psnr_db: float = 0.0
    max_bytes: int = 0
    compare_reencode: bool = False
    report_path: str = ""
    preview_path: str = ""
    html: bool = True
    def __init__(self, **fields: Any) -> None: ...

class Report:
    input_triangles: int
    output_triangles: int
    components: int
    charts: int
    lost_triangles: int
    flipped_triangles: int
    input_texels_used: float
    output_texels_used: float
    surface_psnr_db: float
    surface_psnr_bake_db: float
    texture_sizes: list[tuple[int, int]]
    input_texture_bytes: int
    output_texture_bytes: int
    texture_format: str
    model_path: str
    report_path: str
    wall_seconds: float
    peak_rss_mib: float
    warnings: list[str]
    notes: list[str]
    json: str
    def to_dict(self) -> dict[str, Any]: ...
    def __getitem__(self, key: str) -> Any: ...
    def __contains__(self, key: str) -> bool: ...

class ArraysResult:
    positions: npt.NDArray[np.float64]
    faces: npt.NDArray[np.int64]
    uvs: npt.NDArray[np.float64]
    material_ids: npt.NDArray[np.int64]
    face_materials: npt.NDArray[np.int64]
    materials: list[dict[str, Any]]
    input_triangles: npt.NDArray[np.int64]
    images: list[npt.NDArray[np.uint8]]
    report_html: Optional[str]
    report: Report
    def __getitem__(self, key: str) -> Any: ...
    def keys(self) -> list[str]: ...

def set_max_threads(n: int) -> None: ...
def optimize(input_path: Path, output_dir: Path, options: Optional[Options] = None, progress: Optional[ProgressCallback] = None,
             **fields: Any) -> Report: ...
def estimate_memory(input_path: Path, options: Optional[Options] = None, **fields: Any) -> int: ...
def optimize_arrays(
    positions: npt.ArrayLike,
    faces: npt.ArrayLike,
    uvs: npt.ArrayLike,
    images: Union[npt.NDArray[np.uint8], Sequence[npt.NDArray[np.uint8]]],
    material_ids: Optional[npt.ArrayLike] = None,
    face_uvs: Optional[npt.ArrayLike] = None,
    options: Optional[Options] = None,
    progress: Optional[ProgressCallback] = None,
    materials: Optional[Sequence[dict[str, Any]]] = None,
    colors: Optional[npt.ArrayLike] = None,
    html: bool = False,
    **fields: Any,
) -> ArraysResult: ...
