"""Tighten Textures: tightex in Blender. The selected scans' textures re-baked into one compact chart
per surface, in place (a new UV map, new images, material copies), with its figures and one undo step."""

bl_info = {
    "name": "tightex: Tighten Textures",
    "description": "One compact texture chart per surface for textured scans (tightex), in place",
    "author": "tightex",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Object > Tighten Textures; UV Editor > UV > Tighten Textures; 3D View sidebar > tightex",
    "category": "UV",
}

import bpy

from . import library, operator, ui


class TightexPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    module_folder: bpy.props.StringProperty(
        name="tightex module folder", subtype="DIR_PATH",
        description="The folder that holds the Python package tightex (e.g. BUILD/python); empty: the installed one",
        update=lambda self, context: library.forget())
    images_beside: bpy.props.BoolProperty(
        name="Save images beside the .blend",
        description="Write the new images into a folder beside the saved .blend instead of packing them into it")

    def draw(self, context):
        self.layout.prop(self, "module_folder")
        self.layout.prop(self, "images_beside")
        module, error = library.load()
        if module is None:
            box = self.layout.box()
            box.alert = True
            for line in error.splitlines():
                box.label(text=line, icon="ERROR")
        else:
            self.layout.label(text=f"tightex found: {module.__file__}", icon="CHECKMARK")


classes = (TightexPreferences, *operator.classes, *ui.classes)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    ui.register_menus()


def unregister():
    ui.unregister_menus()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
