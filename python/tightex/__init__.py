"""tightex: one compact texture per surface, from a scan's fragmented UV atlas.

The Python face of the tightex library (C++, pybind11), on the library's own types:

- ``Options``: what a run chooses, one typed attribute per field with the command's default and its
  ``--help`` text as docstring (``Options(size=1024, map="area")``; a choice is given by name).
- ``optimize(input_path, output_dir, options=None, **fields)`` runs the library's whole run on a model
  file (OBJ, PLY, glTF or GLB with its textures) and returns its ``Report``.
- ``optimize_arrays(positions, faces, uvs, images, ...)`` runs it on an in-memory mesh (NumPy arrays,
  as trimesh or Open3D hold them) and returns an ``ArraysResult``: the new mesh as arrays, and the report.
- ``estimate_memory(input_path, options=None, **fields)`` is the memory the run's guard estimates, from
  the model's geometry and its images' headers.
- ``Report``: the main figures as attributes (``surface_psnr_db``, ``lost_triangles``, ``warnings``,
  ...), ``to_dict()`` for the whole report as report.json holds it, and ``report["metrics"]`` for a section
  (the JSON is parsed once, on first use).

Fields given as keywords are set on a copy of ``options`` (or of the defaults): a keyword that is not a
field raises ``TypeError``, as for any Python function, and so does a value of the wrong type; a value
out of range raises ``InputError``.

Errors: ``InputError`` (bad input, one line naming the file or array, the element and the problem),
``InternalError`` (a bug), ``Cancelled`` (the progress callback returned False); all subclass ``Error``.

``progress(stage: str, fraction: float) -> bool | None`` is called as the run goes ("read", "repair",
"components", "cut+map", "bake", "encode", "measure", "write", and "done" once every file is in place);
returning False cancels it, and nothing is written. tightex releases the GIL while it
works, so other Python threads run meanwhile.
"""

from . import _tightex
from ._tightex import Cancelled, Error, InputError, InternalError, Report

#: The build's version: the string `tightex --version` prints and report.json's "tightex_version".
__version__: str = _tightex.__version__

__all__ = ["Options", "Report", "ArraysResult", "optimize", "optimize_arrays", "estimate_memory", "set_max_threads", "Error",
           "InputError", "InternalError", "Cancelled", "FIELDS"]

#: The names of the fields of Options, as the library declares them.
FIELDS = tuple(name for name in dir(_tightex.Options) if not name.startswith("_"))


def _check_field(name):
    """Raises TypeError, as Python does for an unexpected keyword, unless ``name`` is a field."""
    if name not in FIELDS:
        raise TypeError(f"{name!r} is not a field of tightex.Options (they are: {', '.join(FIELDS)})")


class Options(_tightex.Options):
    __doc__ = _tightex.Options.__doc__

    def __init__(self, **fields):
        """Options with the command's defaults, and ``fields`` set (a keyword that is not a field:
        TypeError)."""
        super().__init__()
        for name, value in fields.items():
            _check_field(name)
            setattr(self, name, value)

    def __repr__(self):
        changed = {name: getattr(self, name) for name in FIELDS if getattr(self, name) != getattr(_DEFAULTS, name)}
        return "tightex.Options(" + ", ".join(f"{k}={v!r}" for k, v in changed.items()) + ")"


_DEFAULTS = _tightex.Options()


def _with_fields(options, fields):
    """A copy of ``options`` (the defaults where None) with ``fields`` set."""
    copy = Options()
    if options is not None:
        for name in FIELDS:
            setattr(copy, name, getattr(options, name))
    for name, value in fields.items():
        _check_field(name)
        setattr(copy, name, value)
    return copy


def optimize(input_path, output_dir, options=None, progress=None, **fields):
    """Optimizes the model at ``input_path`` into ``output_dir``, as the ``tightex`` command does.

    Writes ``output_dir/<name>.obj`` (or ``.ply``, ``.gltf``, ``.glb``: the input's kind, or
    ``model_format``) with its material and textures, ``report.json`` and ``report.html``, each
    atomically; the input is never written to. Returns the ``Report``.

    Raises InputError for a bad model, option or output folder, or a run above ``max_memory_mib``;
    Cancelled when ``progress`` returned False (nothing is written then); InternalError for a bug.
    """
    return _tightex.run(str(input_path), str(output_dir), _with_fields(options, fields), progress)


def estimate_memory(input_path, options=None, **fields):
    """The bytes of memory the run's guard estimates for optimizing ``input_path`` with these options
    (decoded input textures, the mesh and its stages, the output texture), from the model's geometry
    and its images' headers alone. Raises InputError for a model that cannot be read."""
    return int(_tightex.estimate_memory(str(input_path), _with_fields(options, fields)))


class ArraysResult:
    """What ``optimize_arrays`` returns: the optimized mesh as NumPy arrays, and its ``Report``.

    positions: (V, 3) float64, the input's; faces: (F, 3) int64, the input's triangles (in another order,
    each maybe rotated, never flipped); uvs: (F, 3, 2) float64 per corner, in [0, 1]; material_ids: (F,)
    int64, the image of each face; face_materials: (F,) int64, the material of each face in
    ``materials`` (dicts as ``optimize_arrays`` takes, each with its "name"); input_triangles: (F,)
    int64, the input triangle each face is; images: a list of H x W x 4 uint8 arrays; report_html: the
    run's report.html (with ``html=True``, else None); report: the ``Report``.
    ``result["positions"]`` reads the same attributes, as the dict this used to be did.
    """

    __slots__ = ("positions", "faces", "uvs", "material_ids", "face_materials", "materials", "input_triangles", "images",
                 "report_html", "report")

    def __init__(self, arrays, report):
        """The arrays (optimize_arrays's, by name; absent ones None) and the report."""
        for name in self.__slots__:
            setattr(self, name, arrays.get(name))
        self.report = report

    def __getitem__(self, key):
        """The attribute ``key`` (KeyError for another name): the former dict's access."""
        if key not in self.__slots__:
            raise KeyError(key)
        return getattr(self, key)

    def keys(self):
        """The names of the attributes, as the former dict's keys."""
        return list(self.__slots__)

    def __repr__(self):
        return (f"tightex.ArraysResult({len(self.positions)} positions, {len(self.faces)} faces, "
                f"{len(self.images)} images)")


def _numeric(name, array, integer):
    """``array`` as a NumPy array, refused (TypeError naming it) unless its dtype is an integer (for
    indices) or a real number (for coordinates): a float index array is not silently truncated."""
    import numpy as np

    a = np.asarray(array)
    if integer and not np.issubdtype(a.dtype, np.integer):
        raise TypeError(f"arrays: {name} must be an integer array (indices), not {a.dtype}")
    if not integer and not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)):
        raise TypeError(f"arrays: {name} must be an array of real numbers, not {a.dtype}")
    return a


def optimize_arrays(positions, faces, uvs, images, material_ids=None, face_uvs=None, options=None, progress=None, materials=None,
                    colors=None, html=False, **fields):
    """Optimizes an in-memory textured mesh; nothing is read or written.

    positions: (V, 3) float; faces: (F, 3) int, counter-clockwise front.
    uvs: texture coordinates, OBJ convention (v up; row 0 of an image is v = 1), one of
      - (F, 3, 2): per corner (Open3D's ``triangle_uvs.reshape(-1, 3, 2)``; Open3D holds a texture it
        read bottom row first: pass ``np.asarray(texture)[::-1]``, and flip the images returned back);
      - (T, 2) with ``face_uvs`` (F, 3) indexing it (as an OBJ's ``vt`` and its face indices);
      - (V, 2) per vertex without ``face_uvs`` (trimesh's ``visual.uv``).
    images: a list of H x W x 3 or H x W x 4 uint8 arrays (one array alone is taken as a list of one).
    material_ids: (F,) int, the image (or, with ``materials``, the material) of each face (-1: none);
      default: every face the first.
    materials: None (one material per image), or a list of dicts, each with "texture" (its base colour
      image, -1: none), "kd" (its linear base colour factor, as glTF's) and "maps" ({slot: image}; the
      slots "metallic_roughness", "occlusion", "emissive", "normal" (tangent space), "specular",
      "roughness", "metallic", "bump"); images may then be empty.
    colors: (F, 3, 4) float vertex colours per corner, sRGB in [0, 1], baked into a new image as the
      command does for a vertex-coloured model.
    html: also return "report_html", the text of the run's report.html.
    options, fields: as for ``optimize`` (those about written files do nothing here).

    Returns an ``ArraysResult`` (``.positions``, ``.faces``, ``.uvs``, ``.material_ids``, ``.images``,
    ``.face_materials``, ``.materials``, ``.input_triangles``, ``.report_html``, ``.report``).

    Raises TypeError naming the array for a wrong dtype (float faces, face_uvs or material_ids; images
    not uint8); InputError naming the array and element for a bad shape or index; Cancelled; InternalError.
    """
    import numpy as np

    if isinstance(images, np.ndarray):
        images = [images]
    images = [np.asarray(image) for image in images]
    for i, image in enumerate(images):
        if image.dtype != np.uint8:
            raise TypeError(f"arrays: images[{i}] is {image.dtype}, not uint8 (0..255 per channel)")
    positions, uvs = _numeric("positions", positions, False), _numeric("uvs", uvs, False)
    faces = _numeric("faces", faces, True)
    if material_ids is not None:
        material_ids = _numeric("material_ids", material_ids, True)
    if face_uvs is not None:
        face_uvs = _numeric("face_uvs", face_uvs, True)
    arrays, report = _tightex.optimize_arrays(positions, faces, uvs, images, material_ids, face_uvs, _with_fields(options, fields),
                                              progress, materials, colors, bool(html))
    return ArraysResult(arrays, report)


def set_max_threads(n):
    """At most ``n`` threads for tightex's parallel work in this process from now on (0: one per core,
    the default). A process sharing the machine with others (a Dask worker) takes its share."""
    _tightex.set_max_threads(int(n))
