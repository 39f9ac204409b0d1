"""Blender with its UI (under xvfb-run): the add-on's modal run (INVOKE: worker thread, progress) on a
scan, then a screenshot of Blender showing the result and its figures. First, headless, the scene is
made (the model imported, scaled to a metre) and saved as OUT.blend; Blender then opens it with its UI
(a file given: no splash screen):

    blender -b --factory-startup --python blender/screenshot.py -- BUILD MODEL OUT.png
    xvfb-run -s "-screen 0 1280x720x24" blender --factory-startup OUT.blend --python blender/screenshot.py -- BUILD MODEL OUT.png
"""

import os
import sys

import bpy

BUILD, MODEL, OUT = sys.argv[sys.argv.index("--") + 1:][:3]
seen = {"status": set(), "phase": "run", "ticks": 0}


def context_3d():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return {"window": window, "screen": window.screen, "area": area, "region": region}


def make_scene():
    """Headless: the model imported into an empty scene, a metre high, saved as OUT.blend."""
    bpy.ops.wm.read_homefile(use_empty=True)
    if MODEL.endswith(".obj"):
        bpy.ops.wm.obj_import(filepath=MODEL)
    else:
        import numpy
        numpy.bool = bool  # Debian 12's Blender 3.4 glTF add-on still names np.bool, gone from NumPy 1.24
        bpy.ops.import_scene.gltf(filepath=MODEL)
    obj = next(o for o in bpy.data.objects if o.type == "MESH")
    obj.scale *= 1.0 / max(obj.dimensions)
    bpy.ops.wm.save_as_mainfile(filepath=OUT.replace(".png", ".blend"))


def setup():
    bpy.ops.preferences.addon_install(filepath=os.path.join(BUILD, "tightex_blender.zip"), overwrite=True)
    bpy.ops.preferences.addon_enable(module="tightex_blender")
    bpy.context.preferences.addons["tightex_blender"].preferences.module_folder = os.path.join(BUILD, "python")
    obj = next(o for o in bpy.data.objects if o.type == "MESH")
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    ctx = context_3d()
    with bpy.context.temp_override(**ctx):
        bpy.ops.view3d.view_selected()
        print("invoke:", bpy.ops.object.tighten_textures("INVOKE_DEFAULT"))
    return None


def show_result():
    """The 3D view in Material Preview without its sidebar; the Properties editor's Object tab filtered
    to the add-on's panel of figures (set once the run is over: redraws on a software GL are slow)."""
    space = context_3d()["area"].spaces[0]
    space.shading.type = "MATERIAL"
    space.show_region_ui = False
    for area in bpy.context.window_manager.windows[0].screen.areas:
        if area.type == "PROPERTIES":
            area.spaces[0].context = "OBJECT"
            area.spaces[0].search_filter = "tightex"


def shrink(path):
    """The screenshot in 256 colours (a third of its bytes), where Pillow is installed (python3-pil)."""
    try:
        from PIL import Image
    except ImportError:
        return
    Image.open(path).convert("RGB").quantize(256, dither=Image.Dither.NONE).save(path, optimize=True)


def watch():
    """Waits for the run's figures; then the screenshot."""
    seen["ticks"] += 1
    figures = bpy.context.scene.get("tightex_figures")
    if figures and seen["phase"] == "run":
        print("figures:", figures, "after", seen["ticks"], "polls")
        seen["phase"] = "shot"
        show_result()
        return 3.0
    if seen["phase"] == "shot":
        ctx = context_3d()
        with bpy.context.temp_override(**ctx):
            bpy.ops.screen.screenshot(filepath=OUT)
        shrink(OUT)
        print("screenshot:", OUT, os.path.getsize(OUT), "bytes")
        bpy.ops.wm.quit_blender()
        return None
    if seen["ticks"] == 30 and os.environ.get("TIGHTEX_SCREENSHOT_RUNNING"):  # the status bar while it runs
        with bpy.context.temp_override(**context_3d()):
            bpy.ops.screen.screenshot(filepath=os.environ["TIGHTEX_SCREENSHOT_RUNNING"])
    if seen["ticks"] > 600:
        print("timed out")
        bpy.ops.wm.quit_blender()
    return 0.1


if bpy.app.background:
    make_scene()
else:
    bpy.app.timers.register(setup, first_interval=1.0)
    bpy.app.timers.register(watch, first_interval=2.0)
