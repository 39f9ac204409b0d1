"""The add-on "Tighten Textures" in Blender, headless (tests/blender/run.sh runs it):

    blender -b --factory-startup --python-exit-code 1 --python test_addon.py -- BUILD SOURCE WORK

Installs and enables BUILD/tightex_blender.zip (the tightex module found through its preference), then
on a real scan imported with Blender's own importers (OBJ: fuze; glTF: the Khronos avocado): a run
cancelled at its first progress event changes nothing; the operator keeps every face and corner
position, gives a new active UV map with one chart per connected surface and >= 99 % of its texels
used, and a surface PSNR (both materials exported with Blender's glTF exporter, measured by `tightex
measure`) at least the command line's on the same export less 0.3 dB; the export is glTF-Validator
clean where tests/gltf's validator is installed; a second run finds the result already tight; undo
restores the objects. A vertex-coloured sphere checks the options (size, removal, report.html). Exits 1 on a
failed check.
"""

import hashlib
import json
import os
import subprocess
import sys
import traceback

import bpy
import numpy as np

BUILD, SOURCE, WORK = sys.argv[sys.argv.index("--") + 1:][:3]
DATA = os.path.join(SOURCE, "..", "shared", "data")
failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        failures.append(what)


def model_paths():
    """(name, path) of the scans to run on, those present."""
    fuze = next((p for p in (os.path.join(SOURCE, "tests", "data", "fuze", "fuze.obj"), os.path.join(DATA, "fuze", "fuze.obj"))
                 if os.path.exists(p)), None)
    avocado = os.path.join(DATA, "khronos_avocado", "Avocado.glb")
    out = []
    for name, path in (("fuze (OBJ)", fuze), ("avocado (glTF)", avocado)):
        if path and os.path.exists(path):
            out.append((name, path))
        else:
            print(f"SKIP  {name}: not found (tests/data or ../shared/data)")
    return out


def install_addon():
    bpy.ops.preferences.addon_install(filepath=os.path.join(BUILD, "tightex_blender.zip"), overwrite=True)
    bpy.ops.preferences.addon_enable(module="tightex_blender")
    prefs = bpy.context.preferences.addons["tightex_blender"].preferences
    import tightex_blender.library as library
    # Without the module the add-on says so: the operator refuses with the reason.
    saved = sys.modules.get("tightex")
    sys.modules["tightex"] = None
    library.forget()
    module, error = library.load()
    check(module is None and "Cannot import tightex" in error, f"no module: the add-on says why ({error.splitlines()[0]!r})")
    if saved is None:
        del sys.modules["tightex"]
    else:
        sys.modules["tightex"] = saved
    prefs.module_folder = os.path.join(BUILD, "python")
    module, error = library.load()
    check(module is not None and module.__file__.startswith(os.path.join(BUILD, "python")),
          f"the module from the preference's folder ({module.__file__ if module else error})")


def import_model(path):
    """The model imported by Blender's own importer into an empty scene; its mesh objects, selected."""
    bpy.ops.wm.read_homefile(use_empty=True)
    if path.endswith(".obj"):
        bpy.ops.wm.obj_import(filepath=path)
    else:
        np.bool = bool  # Debian 12's Blender 3.4 glTF add-on still names np.bool, gone from NumPy 1.24
        bpy.ops.import_scene.gltf(filepath=path)
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    for o in bpy.data.objects:
        o.select_set(o in meshes)
    bpy.context.view_layer.objects.active = meshes[0]
    return [o.name for o in meshes]


def _bytes(collection, attr, dtype, width=1):
    a = np.empty(len(collection) * width, dtype)
    collection.foreach_get(attr, a)
    return a.tobytes()


def snapshot():
    """Everything the add-on may change, as bytes: meshes (positions, faces, UV maps, material slots and
    indices), materials (their image nodes), images (pixels)."""
    s = {}
    for mesh in bpy.data.meshes:
        s["mesh " + mesh.name] = (_bytes(mesh.vertices, "co", np.float32, 3), _bytes(mesh.loops, "vertex_index", np.int32),
                                  _bytes(mesh.polygons, "loop_start", np.int32), _bytes(mesh.polygons, "material_index", np.int32),
                                  [(uv.name, uv.active, uv.active_render, _bytes(uv.data, "uv", np.float32, 2)) for uv in mesh.uv_layers],
                                  [m.name if m else None for m in mesh.materials])
    for m in bpy.data.materials:
        s["material " + m.name] = [(n.name, n.image.name if getattr(n, "image", None) else None) for n in m.node_tree.nodes] if m.node_tree else []
    for image in bpy.data.images:
        pixels = np.empty(len(image.pixels), np.float32)
        image.pixels.foreach_get(pixels)
        s["image " + image.name] = (tuple(image.size), image.filepath, hashlib.sha256(pixels.tobytes()).hexdigest())
    return s


def _corner_positions(mesh):
    co = np.frombuffer(_bytes(mesh.vertices, "co", np.float32, 3), np.float32).reshape(-1, 3)
    return co[np.frombuffer(_bytes(mesh.loops, "vertex_index", np.int32), np.int32)]


def _components(tri_pos, tri_uv, by_uv):
    """The connected components of the triangles, through edges shared by position (and, where by_uv,
    the same texture coordinates at both ends)."""
    parent = list(range(len(tri_pos)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    edges = {}
    for t in range(len(tri_pos)):
        for c in range(3):
            a, b = (tri_pos[t][c], tri_uv[t][c]), (tri_pos[t][(c + 1) % 3], tri_uv[t][(c + 1) % 3])
            key = tuple(sorted([a, b] if by_uv else [(a[0],), (b[0],)]))
            if key in edges:
                parent[find(t)] = find(edges[key])
            else:
                edges[key] = t
    return len({find(t) for t in range(len(tri_pos))})


def charts_and_surfaces(mesh):
    mesh.calc_loop_triangles()
    loops = np.frombuffer(_bytes(mesh.loop_triangles, "loops", np.int32, 3), np.int32).reshape(-1, 3)
    pos = _corner_positions(mesh)[loops]
    uv = np.frombuffer(_bytes(mesh.uv_layers.active.data, "uv", np.float32, 2), np.float32).reshape(-1, 2)[loops]
    tri_pos = [[tuple(p) for p in t] for t in pos.tolist()]
    tri_uv = [[tuple(p) for p in t] for t in uv.tolist()]
    return _components(tri_pos, tri_uv, True), _components(tri_pos, tri_uv, False), uv


def texels_used(uv, width, height):
    """Fraction of the texel centres of a W x H image inside at least one of the triangles (METRICS.md)."""
    covered = np.zeros((height, width), bool)
    p = uv.astype(np.float64) * [width, height]
    for a, b, c in p:
        lo = np.floor(np.minimum(np.minimum(a, b), c) - 0.5).astype(int).clip(0, [width - 1, height - 1])
        hi = np.ceil(np.maximum(np.maximum(a, b), c) - 0.5).astype(int).clip(0, [width - 1, height - 1])
        x, y = np.meshgrid(np.arange(lo[0], hi[0] + 1) + 0.5, np.arange(lo[1], hi[1] + 1) + 0.5)
        d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        if d == 0:
            continue
        w1 = ((x - a[0]) * (c[1] - a[1]) - (y - a[1]) * (c[0] - a[0])) / d
        w2 = ((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])) / d
        inside = (w1 >= -1e-9) & (w2 >= -1e-9) & (w1 + w2 <= 1 + 1e-9)
        covered[lo[1]:hi[1] + 1, lo[0]:hi[0] + 1] |= inside
    return covered.mean()


def export_glb(path):
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLB", use_selection=True, export_tangents=True)
    return path


def tightex(*args):
    out = subprocess.run([os.path.join(BUILD, "tightex"), *args], capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"tightex {' '.join(args)}: {out.stderr.strip()}")
    return out.stdout


def validate(path):
    checks = os.path.join(SOURCE, "tests", "gltf")
    if not os.path.isdir(os.path.join(checks, "node_modules", "gltf-validator")):
        print("SKIP  glTF-Validator: tests/gltf/node_modules is missing (bash scripts/gltf-checks.sh)")
        return
    out = subprocess.run(["node", os.path.join(checks, "check_gltf.mjs"), path], capture_output=True, text=True)
    r = json.loads(out.stdout.strip().splitlines()[-1]) if out.stdout.strip() else {"unparsed": out.stderr}
    check(r.get("errors") == 0 and r.get("warnings") == 0 and "load_error" not in r, f"glTF-Validator: {r}")


def cancel_changes_nothing(names):
    """A run cancelled at its first progress event: tightex.Cancelled, and the .blend as it was."""
    from tightex_blender import run
    import tightex
    before = snapshot()
    events = []
    try:
        run.tighten([bpy.data.objects[n] for n in names], {}, progress=lambda i, stage, f: events.append(stage) or False)
        check(False, "cancel: the run was not cancelled")
    except tightex.Cancelled:
        check(len(events) == 1, f"cancel: stopped at the first progress event ({events})")
    check(snapshot() == before, "cancel: meshes, UV maps, materials and images byte-identical")


def case(name, path):
    print(f"== {name}: {path}", flush=True)
    names = import_model(path)
    obj = bpy.data.objects[names[0]]
    cancel_changes_nothing(names)
    before = snapshot()
    faces, corners = len(obj.data.polygons), _corner_positions(obj.data).copy()
    before_glb = export_glb(os.path.join(WORK, f"{obj.name}_before.glb"))
    bpy.ops.ed.undo_push(message="before tightex")
    result = bpy.ops.object.tighten_textures()
    check(result == {"FINISHED"}, f"operator: {result}")
    # Blender's UI pushes the undo step of an operator with UNDO once it finishes; headless, no window
    # does, so the test pushes it as the UI would.
    bpy.ops.ed.undo_push(message="Tighten Textures")
    figures = json.loads(bpy.context.scene["tightex_figures"])[0]
    print("      figures:", figures)
    obj = bpy.data.objects[names[0]]
    mesh = obj.data
    check(len(mesh.polygons) == faces and np.array_equal(_corner_positions(mesh), corners),
          f"geometry: {len(mesh.polygons)} faces (was {faces}), corner positions unchanged")
    check(mesh.uv_layers.active.name == "tightex" and len(mesh.uv_layers) == 2, "a new active UV map, the old one kept")
    charts, surfaces, uv = charts_and_surfaces(mesh)
    check(charts == surfaces, f"one chart per connected surface: {charts} charts, {surfaces} surfaces")
    new_nodes = [n for m in mesh.materials if m.name.endswith("_tightex") for n in m.node_tree.nodes if n.type == "TEX_IMAGE"]
    old_images = {n.image.name for m in bpy.data.materials if not m.name.endswith("_tightex") and m.node_tree
                  for n in m.node_tree.nodes if n.type == "TEX_IMAGE" and n.image}
    new_images = {n.image.name for n in new_nodes if n.image}
    check(new_nodes and all(n.image and n.image.name.startswith(obj.name + "_tightex") for n in new_nodes)
          and len(new_images) == len(old_images), f"every image node of the new material shows a new image: {sorted(new_images)}")
    base = new_nodes[0].image
    used = texels_used(uv.reshape(-1, 3, 2), *base.size)
    check(used >= 0.99, f"texels used {100 * used:.2f} % of {base.size[0]}x{base.size[1]} >= 99 %")
    check(base.packed_file is not None, f"new image {base.name} packed into the .blend")
    after_glb = export_glb(os.path.join(WORK, f"{obj.name}_after.glb"))
    addon_psnr = json.loads(tightex("measure", before_glb, after_glb))["surface_psnr_db"]
    tightex(before_glb, "--output", os.path.join(WORK, f"{obj.name}_cli"))
    cli = json.load(open(os.path.join(WORK, f"{obj.name}_cli", "report.json")))["metrics"]["surface_psnr_db"]
    check(addon_psnr >= cli - 0.3, f"surface PSNR {addon_psnr:.2f} dB (Blender's exports, tightex measure) >= the command's "
                                   f"{cli:.2f} dB - 0.3")
    validate(after_glb)
    again = bpy.ops.object.tighten_textures()
    refigures = json.loads(bpy.context.scene["tightex_figures"])[0]
    check(again == {"FINISHED"} and refigures["already_tight"], f"a second run: already tight ({refigures['charts']} charts)")
    undo(before)


def undo(before):
    """One undo step back: the .blend as it was before the run."""
    try:
        bpy.ops.ed.undo()
    except RuntimeError as e:
        print(f"SKIP  undo: cannot be exercised headless here ({str(e).splitlines()[0]})")
        return
    check(snapshot() == before, "one undo step restores meshes, UV maps, materials and images")


def vertex_coloured_case():
    """A vertex-coloured sphere (no material): baked into a new image of the size asked, the old UV map
    and unused data removed, report.html written, as the redo panel's options ask."""
    print("== vertex colours, options", flush=True)
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16)
    obj = bpy.context.active_object
    mesh = obj.data
    co = np.array([v.co for v in mesh.vertices])
    attr = mesh.color_attributes.new("Col", "BYTE_COLOR", "POINT")
    attr.data.foreach_set("color", np.concatenate([co * 0.5 + 0.5, np.ones((len(co), 1))], 1).astype(np.float32).ravel())
    mesh.color_attributes.active_color = attr
    faces, corners = len(mesh.polygons), _corner_positions(mesh).copy()
    report = os.path.join(WORK, "sphere_report.html")
    result = bpy.ops.object.tighten_textures(budget="SIZE", size=256, old_uv="REMOVE", old_data="REMOVE", write_report=True,
                                             report_path=report)
    check(result == {"FINISHED"} and len(mesh.polygons) == faces and np.array_equal(_corner_positions(mesh), corners),
          "vertex colours: run, geometry unchanged")
    check([u.name for u in mesh.uv_layers] == ["tightex"], f"old UV map removed: {[u.name for u in mesh.uv_layers]}")
    images = [n.image for m in mesh.materials for n in m.node_tree.nodes if n.type == "TEX_IMAGE" and n.image]
    check(len(images) == 1 and tuple(images[0].size) == (256, 256), f"the colours baked into one 256x256 image: {images}")
    check(os.path.exists(report) and "<html" in open(report, encoding="utf-8").read(2000).lower(), "report.html written")


def main():
    models = model_paths()
    install_addon()
    try:
        vertex_coloured_case()
    except Exception:
        traceback.print_exc()
        failures.append("vertex colours: an exception")
    for name, path in models:
        try:
            case(name, path)
        except Exception:
            traceback.print_exc()
            failures.append(f"{name}: an exception")
    print(f"{len(failures)} failed" + (": " + "; ".join(failures) if failures else ""), flush=True)
    sys.exit(1 if failures else 0)


main()
