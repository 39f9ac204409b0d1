"""By hand (not in ctest: it needs Xvfb, and a software GL makes it slow): the operator run from
Blender's UI (INVOKE: the modal path, tightex on a worker thread), Esc pressed while it runs, and the
scene checked a minute later: no figures, the mesh's UV maps, materials and the .blend's images as before.

    xvfb-run -s "-screen 0 1280x720x24" blender --factory-startup --enable-event-simulate SCENE.blend \\
        --python tests/blender/ui_cancel.py -- BUILD

SCENE.blend: one textured mesh (blender/screenshot.py's first step makes one). Prints "ESC: ok" or "ESC: FAIL".
"""

import sys
import time

import bpy

BUILD = sys.argv[sys.argv.index("--") + 1]
log = {"ticks": 0}


def state():
    mesh = next(o for o in bpy.data.objects if o.type == "MESH").data
    return ([u.name for u in mesh.uv_layers], len(bpy.data.images), len(bpy.data.materials), [m.name for m in mesh.materials])


def start():
    bpy.ops.preferences.addon_install(filepath=BUILD + "/tightex_blender.zip", overwrite=True)
    bpy.ops.preferences.addon_enable(module="tightex_blender")
    bpy.context.preferences.addons["tightex_blender"].preferences.module_folder = BUILD + "/python"
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    obj = next(o for o in bpy.data.objects if o.type == "MESH")
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    log["before"] = state()
    with bpy.context.temp_override(window=window, area=area, region=area.regions[-1]):
        print("invoke:", bpy.ops.object.tighten_textures("INVOKE_DEFAULT"))
    log["t0"] = time.monotonic()


def tick():
    """Esc on the fifth poll; a minute on (the run takes about 30 s here), the verdict."""
    log["ticks"] += 1
    window = bpy.context.window_manager.windows[0]
    if log["ticks"] == 5:
        window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=500, y=300)
        window.event_simulate(type="ESC", value="PRESS")
        window.event_simulate(type="ESC", value="RELEASE")
        print(f"Esc sent {time.monotonic() - log['t0']:.1f} s into the run", flush=True)
    if time.monotonic() - log["t0"] > 60:
        ok = bpy.context.scene.get("tightex_figures") is None and state() == log["before"]
        print("ESC:", "ok" if ok else "FAIL", state(), flush=True)
        bpy.ops.wm.quit_blender()
        return None
    return 0.5


bpy.app.timers.register(start, first_interval=1.0)
bpy.app.timers.register(tick, first_interval=1.2)
