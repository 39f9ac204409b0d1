from typing import Any, Callable, Optional, Sequence, Union
from os import PathLike

import numpy as np
import numpy.typing as npt

ProgressCallback = Callable[[str, float], Optional[bool]]
Path = Union[str, PathLike]

class Error(Exception): ...
class InputError(Error): ...
class InternalError(Error): ...
class Cancelled(Error): ...

def options_to_args(**options: Any) -> list[str]: ...
def optimize(input_path: Path, output_dir: Path, progress: Optional[ProgressCallback] = None, **options: Any) -> dict[str, Any]: ...
def estimate_memory(input_path: Path, **options: Any) -> int: ...
def optimize_arrays(
    positions: npt.ArrayLike,
    faces: npt.ArrayLike,
    uvs: npt.ArrayLike,
    images: Union[npt.NDArray[np.uint8], Sequence[npt.NDArray[np.uint8]]],
    material_ids: Optional[npt.ArrayLike] = None,
    face_uvs: Optional[npt.ArrayLike] = None,
    progress: Optional[ProgressCallback] = None,
    **options: Any,
) -> dict[str, Any]: ...
