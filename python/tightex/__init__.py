"""tightex: one compact texture per surface, from a scan's fragmented UV atlas.

The Python face of the tightex command and library (C++, pybind11):

- ``optimize(input_path, output_dir, **options)`` runs the ``tightex`` command on a model file (OBJ or
  PLY with its textures) and returns its report (``report.json``) as a dict.
- ``optimize_arrays(positions, faces, uvs, images, ...)`` runs it on an in-memory mesh (NumPy arrays,
  as trimesh or Open3D hold them) and returns the new mesh as arrays, with the report.
- ``estimate_memory(input_path, **options)`` is the memory the command's ``--max-memory`` guard
  estimates for a run, from the model's geometry and its images' headers.

Options are the command's (``tightex --help``) as keyword arguments, dashes as underscores:
``size=1024``, ``map="area"``, ``no_fit=True``, ``output_format="ply"``, ``max_memory=2048``. They are
parsed and checked by the command's own code, so defaults and limits are the same; a bad one raises
``InputError``. A flag is given by ``True``; ``False`` or ``None`` leaves an option out.

Errors: ``InputError`` (bad input, one line naming the file or array, the element and the problem),
``InternalError`` (a bug), ``Cancelled`` (the progress callback returned False); all subclass ``Error``.

``progress(stage: str, fraction: float) -> bool | None`` is called as the run goes ("repair",
"components", "cut+map", "bake", ...); returning False cancels it. tightex releases the GIL while it
works, so other Python threads run meanwhile.
"""

import json

from . import _tightex
from ._tightex import Cancelled, Error, InputError, InternalError

__all__ = ["optimize", "optimize_arrays", "estimate_memory", "options_to_args", "set_max_threads", "Error", "InputError", "InternalError", "Cancelled"]


def options_to_args(**options):
    """The command-line arguments for keyword options: ``size=512`` -> ``["--size", "512"]``,
    ``no_fit=True`` -> ``["--no-fit"]``; ``False`` and ``None`` are left out."""
    args = []
    for key, value in options.items():
        name = "--" + key.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            args.append(name)
        else:
            args += [name, str(value)]
    return args


def optimize(input_path, output_dir, progress=None, **options):
    """Optimizes the model at ``input_path`` into ``output_dir``, as the ``tightex`` command does.

    Writes ``output_dir/<name>.obj`` (or ``.ply``: the input's kind, or ``output_format``), its
    material and ``<name>_tightex.png``, and ``report.json``, each atomically; the input is never
    written to. Returns the report as a dict (the METRICS.md figures under "metrics").

    Raises InputError for a bad model, option or output folder, or a run above ``max_memory`` MiB;
    Cancelled when ``progress`` returned False (nothing is written then); InternalError for a bug.
    """
    args = options_to_args(**options)
    return json.loads(_tightex.optimize_file(str(input_path), str(output_dir), args, progress))


def estimate_memory(input_path, **options):
    """The bytes of memory the command's guard estimates for optimizing ``input_path`` with these
    options (decoded input textures, the mesh and its stages, the output texture), from the model's
    geometry and its images' headers alone. Raises InputError for a model that cannot be read."""
    return int(_tightex.estimate_memory(str(input_path), options_to_args(**options)))


def optimize_arrays(positions, faces, uvs, images, material_ids=None, face_uvs=None, progress=None, **options):
    """Optimizes an in-memory textured mesh; nothing is read or written.

    positions: (V, 3) float; faces: (F, 3) int, counter-clockwise front.
    uvs: texture coordinates, OBJ convention (v up; row 0 of an image is v = 1), one of
      - (F, 3, 2): per corner (Open3D's ``triangle_uvs.reshape(-1, 3, 2)``; Open3D holds a texture it
        read bottom row first: pass ``np.asarray(texture)[::-1]``, and flip the images returned back);
      - (T, 2) with ``face_uvs`` (F, 3) indexing it (as an OBJ's ``vt`` and its face indices);
      - (V, 2) per vertex without ``face_uvs`` (trimesh's ``visual.uv``).
    images: a list of H x W x 3 or H x W x 4 uint8 arrays (one array alone is taken as a list of one).
    material_ids: (F,) int, the image of each face (-1: none); default: every face the first image.
    options: the command's (see the module's doc), e.g. ``size=1024``, ``map="area"``.

    Returns a dict: "positions" (V, 3) float64, the input's; "faces" (F, 3) int64, the input's
    triangles (in another order, each maybe rotated, never flipped); "uvs" (F, 3, 2) float64 per
    corner, in [0, 1]; "material_ids" (F,) int64, the image of each face; "images", a list of
    H x W x 4 uint8 arrays; "report", the report as a dict.

    Raises InputError naming the array and element for a bad shape or index; Cancelled; InternalError.
    """
    import numpy as np

    if isinstance(images, np.ndarray):
        images = [images]
    images = [np.asarray(image) for image in images]
    for i, image in enumerate(images):
        if image.dtype != np.uint8:
            raise InputError(f"arrays: images[{i}] is {image.dtype}, not uint8 (0..255 per channel)")
    arrays, report = _tightex.optimize_arrays(positions, faces, uvs, images, material_ids, face_uvs,
                                              options_to_args(**options), progress)
    arrays["report"] = json.loads(report)
    return arrays


def set_max_threads(n):
    """At most ``n`` threads for tightex's parallel work in this process from now on (0: one per core,
    the default). A process sharing the machine with others (a Dask worker) takes its share."""
    _tightex.set_max_threads(int(n))
