"""Where the operator is found (Object menu, the UV editor's UV menu, F3 search) and the panel that
shows the last run's figures (3D View sidebar, tab "tightex", and the Properties editor's Object tab)."""

import json

import bpy

from . import library, run
from .operator import TIGHTEX_OT_tighten_textures


class _Figures:
    """The panel's content: the operator, and the last run's figures per object (or why tightex is missing)."""
    bl_label = "tightex"

    def draw(self, context):
        layout = self.layout
        module, error = library.load()
        if module is None:
            box = layout.box()
            box.alert = True
            for line in error.splitlines():
                box.label(text=line, icon="ERROR")
            return
        layout.operator(TIGHTEX_OT_tighten_textures.bl_idname)
        text = context.scene.get(run.FIGURES_KEY)
        if not text:
            layout.label(text="No run yet")
            return
        for f in json.loads(text):
            box = layout.box()
            box.label(text=f["object"] + ("  (already tight)" if f["already_tight"] else ""), icon="MESH_DATA")
            box.label(text=f"Charts: {f['charts']} ({f['components']} surfaces)")
            box.label(text=f"Texels used: {100 * f['texels_used']:.1f}% (was {100 * f['input_texels_used']:.1f}%)")
            box.label(text=f"Surface PSNR: {f['surface_psnr_db']:.2f} dB")
            box.label(text=f"Time: {f['seconds']:.1f} s")
            if f.get("report_html"):
                box.label(text=f"Report: {f['report_html']}")


class TIGHTEX_PT_figures(_Figures, bpy.types.Panel):
    """In the 3D View's sidebar, tab "tightex"."""
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "tightex"
    bl_idname = "TIGHTEX_PT_figures"


class TIGHTEX_PT_object_figures(_Figures, bpy.types.Panel):
    """The same in the Properties editor's Object tab."""
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"
    bl_idname = "TIGHTEX_PT_object_figures"


def _menu(self, context):
    self.layout.separator()
    self.layout.operator(TIGHTEX_OT_tighten_textures.bl_idname, icon="UV")


def register_menus():
    bpy.types.VIEW3D_MT_object.append(_menu)
    bpy.types.IMAGE_MT_uvs.append(_menu)


def unregister_menus():
    bpy.types.VIEW3D_MT_object.remove(_menu)
    bpy.types.IMAGE_MT_uvs.remove(_menu)


classes = (TIGHTEX_PT_figures, TIGHTEX_PT_object_figures)
