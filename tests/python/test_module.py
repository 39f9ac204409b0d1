"""The module tightex: optimize on files, the array API, errors, cancellation, the memory estimate."""
import json
import os
import threading

import numpy as np
import pytest

from conftest import REPO_DATA, SHARED_DATA, make_bad_obj


def check_output(report, folder, name):
    """The written model's report: nothing lost or flipped, the texture used, the files there."""
    m = report["metrics"]
    assert m["lost_triangles"] == 0 and m["flipped"] == 0
    assert m["output"]["utilization"] >= 0.99
    assert m["charts"] == report["preparation"]["components"]
    assert os.path.isfile(os.path.join(folder, name))
    with open(os.path.join(folder, "report.json")) as f:
        assert json.load(f) == report.to_dict()


def test_errors_are_one_family(tightex):
    for e in (tightex.InputError, tightex.InternalError, tightex.Cancelled):
        assert issubclass(e, tightex.Error) and e.__module__ == "tightex"
    assert tightex.optimize.__doc__ and tightex.optimize_arrays.__doc__


def test_optimize_generated_model(tightex, boxes_model, tmp_path):
    stages = []
    report = tightex.optimize(boxes_model, tmp_path / "out", progress=lambda s, f: stages.append((s, f)), map="area")
    check_output(report, tmp_path / "out", "boxes.obj")
    assert report["options"]["map"] == "area" and report["preparation"]["components"] == 12
    names = [s for s, _ in stages]
    assert names[0] == "read" and stages[-1] == ("done", 1.0) and names.count("done") == 1
    assert names.index("repair") < names.index("encode") < names.index("write") < names.index("measure")
    assert all(0 <= f <= 1 for _, f in stages)


def test_optimize_real_scan(tightex, tmp_path):
    model = os.path.join(REPO_DATA, "fuze", "fuze.obj")  # the repository's scan: every checkout has it
    report = tightex.optimize(model, tmp_path, model_format="ply")
    check_output(report, tmp_path, "fuze.ply")
    assert report["metrics"]["input"]["utilization"] < report["metrics"]["output"]["utilization"]


def test_optimize_reports_every_map(tightex, tmp_path):
    model = os.path.join(SHARED_DATA, "khronos_waterbottle", "WaterBottle.glb")
    if not os.path.isfile(model):
        pytest.skip("../shared/data/khronos_waterbottle not present")
    report = tightex.optimize(model, tmp_path, size=512)
    check_output(report, tmp_path, "WaterBottle.glb")
    maps = {m["name"]: m for m in report["maps"]}
    assert set(maps) == {"metallic_roughness", "emissive", "normal"}
    assert maps["metallic_roughness"]["slots"] == ["metallic_roughness", "occlusion"]
    assert all(len(m["sizes"]) == report["pages"]["count"] and m["scale"] > 0 for m in maps.values())
    assert {f["slot"] for f in report["metrics"]["maps"]} == {"metallic_roughness", "occlusion", "emissive", "normal"}


def test_texture_encoding_options(tightex, boxes_model, tmp_path):
    tightex.optimize(boxes_model, tmp_path / "fast", map="area", size=128, html=False)
    tightex.optimize(boxes_model, tmp_path / "best", map="area", size=128, html=False, png_level=9)
    tightex.optimize(boxes_model, tmp_path / "jpg", map="area", size=128, html=False, texture_format="jpg", jpeg_quality=40)
    fast, best = (os.path.getsize(tmp_path / d / "boxes_tightex.png") for d in ("fast", "best"))
    assert best <= fast
    assert os.path.getsize(tmp_path / "jpg" / "boxes_tightex.jpg") > 0


def test_bad_input_raises_input_error_and_writes_nothing(tightex, boxes_model, tmp_path):
    bad = make_bad_obj(tmp_path / "bad.obj")
    out = tmp_path / "out"
    with pytest.raises(tightex.InputError, match="bad.obj"):
        tightex.optimize(bad, out)
    with pytest.raises(tightex.InputError, match="missing.obj"):
        tightex.optimize(tmp_path / "missing.obj", out)
    with pytest.raises(tightex.InputError, match="--size"):
        tightex.optimize(boxes_model, out, size=3)
    with pytest.raises(tightex.InputError, match="--png-level"):
        tightex.optimize(boxes_model, out, png_level=10)
    with pytest.raises(tightex.InputError, match="--jpeg-quality does nothing"):
        tightex.optimize(boxes_model, out, jpeg_quality=80)
    with pytest.raises(TypeError, match="no_such_option"):
        tightex.optimize(boxes_model, out, no_such_option=1)
    with pytest.raises(tightex.InputError, match="input's own folder"):
        tightex.optimize(boxes_model, os.path.dirname(boxes_model))
    assert not out.exists() or not any(out.iterdir())


def test_progress_returning_false_cancels(tightex, boxes_model, tmp_path):
    with pytest.raises(tightex.Cancelled):
        tightex.optimize(boxes_model, tmp_path, progress=lambda stage, f: stage != "bake")
    assert not os.path.exists(tmp_path / "boxes.obj") and not os.path.exists(tmp_path / "report.json")


def test_progress_exception_propagates(tightex, boxes_model, tmp_path):
    def progress(stage, fraction):
        if stage == "cut+map":
            raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        tightex.optimize(boxes_model, tmp_path, progress=progress)


def grid_mesh(n=16):
    """A trimesh-like mesh: a wavy (n+1)^2 grid, per-vertex UVs in the middle of a noise texture."""
    xs, ys = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    positions = np.stack([xs.ravel(), ys.ravel(), 0.1 * np.sin(3 * xs.ravel())], 1)
    a = (np.arange(n)[None, :] + (n + 1) * np.arange(n)[:, None]).ravel()
    faces = np.concatenate([np.stack([a, a + 1, a + n + 2], 1), np.stack([a, a + n + 2, a + n + 1], 1)])
    uvs = positions[:, :2] * 0.5 + 0.25
    image = np.random.default_rng(1).integers(0, 256, (256, 256, 3), dtype=np.uint8)
    return positions, faces, uvs, image


def canonical(faces):
    """Each triangle rotated to start at its smallest index (winding kept), sorted."""
    rolled = [tuple(np.roll(f, -int(np.argmin(f)))) for f in faces]
    return sorted(rolled)


def test_arrays_round_trip(tightex):
    positions, faces, uvs, image = grid_mesh()
    threads = set()
    out = tightex.optimize_arrays(positions, faces, uvs, [image], progress=lambda s, f: threads.add(threading.get_ident()))
    assert np.array_equal(out["positions"], positions)
    assert canonical(out["faces"]) == canonical(faces)
    assert out["uvs"].shape == (len(faces), 3, 2) and out["uvs"].min() >= 0 and out["uvs"].max() <= 1
    side = out["report"]["options"]["size"]
    assert [i.shape for i in out["images"]] == [(side, side, 4)] and out["images"][0].dtype == np.uint8
    # The input's used texels: a quarter of 256^2, so a 128^2 texture.
    assert side == 128
    assert np.all(out["material_ids"] == 0)
    m = out["report"]["metrics"]
    assert m["lost_triangles"] == 0 and m["flipped"] == 0 and m["output"]["utilization"] >= 0.99
    # The same mesh with per-corner UVs, and with UVs indexed per face, gives the same result.
    per_corner = tightex.optimize_arrays(positions, faces, uvs[faces], image)
    indexed = tightex.optimize_arrays(positions, faces, uvs[::-1], image, face_uvs=len(uvs) - 1 - faces)
    for other in (per_corner, indexed):
        assert np.array_equal(other["uvs"], out["uvs"]) and np.array_equal(other["images"][0], out["images"][0])
    # A typed result: attributes, and the former dict's keys reading the same.
    assert isinstance(out, tightex.ArraysResult) and isinstance(out.report, tightex.Report)
    assert out.uvs is out["uvs"] and out.report is out["report"] and set(out.keys()) == {
        "positions", "faces", "uvs", "material_ids", "face_materials", "materials", "input_triangles", "images", "report_html",
        "report"}
    with pytest.raises(KeyError):
        out["mesh"]


def test_arrays_bad_input(tightex):
    positions, faces, uvs, image = grid_mesh(4)
    with pytest.raises(tightex.InputError, match="faces element"):
        tightex.optimize_arrays(positions, faces + len(positions), uvs, image)
    with pytest.raises(tightex.InputError, match="positions has shape"):
        tightex.optimize_arrays(positions[:, :2], faces, uvs, image)
    with pytest.raises(tightex.InputError, match="uvs has 3 rows"):
        tightex.optimize_arrays(positions, faces, uvs[:3], image)
    with pytest.raises(tightex.InputError, match="material_ids"):
        tightex.optimize_arrays(positions, faces, uvs, image, material_ids=np.full(len(faces), 1))
    with pytest.raises(tightex.InputError, match="images"):
        tightex.optimize_arrays(positions, faces, uvs, [image[:, :, 0]])
    with pytest.raises(TypeError, match=r"images\[0\].*not uint8"):
        tightex.optimize_arrays(positions, faces, uvs, [image / 255.0])
    # Indices must be integers: a float array is refused, not truncated.
    with pytest.raises(TypeError, match="faces must be an integer array"):
        tightex.optimize_arrays(positions, faces.astype(float), uvs, image)
    with pytest.raises(TypeError, match="material_ids must be an integer array"):
        tightex.optimize_arrays(positions, faces, uvs, image, material_ids=np.zeros(len(faces)))
    with pytest.raises(TypeError, match="face_uvs must be an integer array"):
        tightex.optimize_arrays(positions, faces, uvs, image, face_uvs=faces * 1.0)
    with pytest.raises(TypeError, match="positions must be an array of real numbers"):
        tightex.optimize_arrays(positions.astype(str), faces, uvs, image)
    with pytest.raises(tightex.Cancelled):
        tightex.optimize_arrays(positions, faces, uvs, image, progress=lambda s, f: False)


def test_arrays_material_maps_colours_and_html(tightex):
    positions, faces, uvs, image = grid_mesh()
    flat_normal = np.full((256, 256, 3), (128, 128, 255), np.uint8)
    materials = [{"texture": 0, "maps": {"normal": 1, "metallic_roughness": 0}}]
    out = tightex.optimize_arrays(positions, faces, uvs, [image, flat_normal], materials=materials, html=True)
    new = out["materials"][out["face_materials"][0]]
    assert new["new"] and set(new["maps"]) == {"normal", "metallic_roughness"}
    # A flat normal stays flat in the new frames; each output face is the input triangle it names.
    assert np.abs(out["images"][new["maps"]["normal"]][..., :3].astype(int) - (128, 128, 255)).max() <= 2
    assert canonical(faces[out["input_triangles"]]) == canonical(out["faces"])
    assert "<html" in out["report_html"].lower()
    with pytest.raises(tightex.InputError, match="not a material slot"):
        tightex.optimize_arrays(positions, faces, uvs, [image], materials=[{"texture": 0, "maps": {"glow": 0}}])
    # Vertex colours alone (no image): baked into a new texture.
    colours = np.random.default_rng(2).random((len(faces), 3, 4)).astype(np.float32)
    baked = tightex.optimize_arrays(positions, faces, uvs, [], materials=[{"texture": -1}], colors=colours)
    assert baked["materials"][baked["face_materials"][0]]["texture"] >= 0 and len(baked["images"]) >= 1


def test_estimate_memory_is_the_guards(tightex, boxes_model, tmp_path):
    small = tightex.estimate_memory(boxes_model, size=256)
    large = tightex.estimate_memory(boxes_model, size=1024)
    # 7 bytes per output texel (RGBA and the bake's masks), the rest the same.
    assert large - small == pytest.approx(7 * (1024**2 - 256**2))
    limit_mib = (small + large) / 2 / 2**20
    with pytest.raises(tightex.InputError, match="--max-memory"):
        tightex.optimize(boxes_model, tmp_path, size=1024, max_memory_mib=limit_mib)
    report = tightex.optimize(boxes_model, tmp_path, size=256, max_memory_mib=limit_mib)
    assert report["options"]["size"] == 256


def stub_fields(cls_name):
    """The attributes and defaults a class of __init__.pyi declares (None where it gives no default)."""
    import ast
    stub = os.path.join(os.path.dirname(__import__("tightex").__file__), "__init__.pyi")
    tree = ast.parse(open(stub).read())
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == cls_name)
    return {n.target.id: (ast.literal_eval(n.value) if n.value is not None else None)
            for n in cls.body if isinstance(n, ast.AnnAssign)}


def test_options_are_the_librarys_typed_fields(tightex):
    options = tightex.Options(size=512, map="area", texture_format="webp")
    assert (options.size, options.map, options.texture_format) == (512, "area", "webp")
    # The stub declares every field with the library's default, and nothing else.
    declared = stub_fields("Options")
    assert set(declared) == set(tightex.FIELDS)
    defaults = tightex.Options()
    for name, default in declared.items():
        assert getattr(defaults, name) == default, name
        assert getattr(tightex.Options, name).__doc__, name  # the --help text
    with pytest.raises(TypeError):
        tightex.Options(size="large")
    with pytest.raises(tightex.InputError, match="map 'bumpy'"):
        tightex.Options(map="bumpy")
    with pytest.raises(TypeError, match="no_such_field"):
        tightex.Options(no_such_field=1)


def test_report_attributes_are_its_figures(tightex, boxes_model, tmp_path):
    options = tightex.Options(map="area", html=False)
    report = tightex.optimize(boxes_model, tmp_path, options, size=128)
    assert options.size == 0  # the keywords went to a copy
    assert set(stub_fields("Report")) == {n for n in dir(report) if not n.startswith("_") and n not in ("to_dict",)}
    d = report.to_dict()
    assert report.lost_triangles == d["metrics"]["lost_triangles"] == 0
    assert report.surface_psnr_db == d["metrics"]["surface_psnr_db"]
    assert report.components == d["preparation"]["components"] == 12
    assert report.texture_sizes == [(128, 128)] and report.input_triangles == report.output_triangles
    assert report.report_path == str(tmp_path / "report.json") and os.path.isfile(report.model_path)
    assert report.output_texture_bytes == d["bytes"]["output"]["total"] > 0
    # The JSON is parsed once: a section is the same object each time; to_dict is a copy to change.
    assert report["metrics"] is report["metrics"] and "metrics" in report
    d["metrics"]["charts"] = -1
    assert report["metrics"]["charts"] == report.charts


def test_every_public_name_has_a_docstring(tightex):
    for name in tightex.__all__:
        value = getattr(tightex, name)
        if callable(value):
            assert value.__doc__ and value.__doc__.strip(), name
    for cls in (tightex.Report, tightex.Options):  # ArraysResult's attributes: its class docstring
        for name in dir(cls):
            if not name.startswith("_"):
                assert getattr(cls, name).__doc__, f"{cls.__name__}.{name}"


def test_size_means_a_square_everywhere(tightex, boxes_model, tmp_path):
    # --size N is a square to the command; the library's size is the same, from a file and from arrays.
    report = tightex.optimize(boxes_model, tmp_path / "file", size=96, html=False)
    assert report.texture_sizes == [(96, 96)]
    positions, faces, uvs, image = grid_mesh()
    out = tightex.optimize_arrays(positions, faces, uvs * np.array([1.0, 0.25]), image, size=64)
    assert [i.shape[:2] for i in out.images] == [(64, 64)]
    # A shape asked for with it is kept.
    report = tightex.optimize(boxes_model, tmp_path / "wide", size=96, aspect=2.0, html=False)
    assert report.texture_sizes[0][0] == 2 * report.texture_sizes[0][1]


def test_the_package_builds_no_command_line(tightex):
    package = os.path.dirname(tightex.__file__)
    for name in os.listdir(package):
        if name.endswith(".py"):
            text = open(os.path.join(package, name)).read()
            assert "options_to_args" not in text and "check_arguments" not in text and "optimize_file" not in text, name
