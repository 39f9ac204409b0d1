"""The operator "Tighten Textures": modal where there is a window (tightex on a worker thread, Blender's
progress indicator and status text following it, Esc cancels), synchronous otherwise (headless, redo)."""

import threading

import bpy

from . import library, run

SETTINGS = ("budget", "size", "megatexels", "map", "page_size", "image_format", "quality", "old_uv", "old_data", "write_report",
            "report_path")


def _object_mode(context):
    """Leaves edit mode (the UV editor's): the mesh's own data is what is read and written."""
    if context.mode != "OBJECT" and context.active_object is not None:
        bpy.ops.object.mode_set(mode="OBJECT")


class TIGHTEX_OT_tighten_textures(bpy.types.Operator):
    """Re-bake the selected meshes' textures into one compact chart per surface (tightex): a new UV map, new images, material copies"""
    bl_idname = "object.tighten_textures"
    bl_label = "Tighten Textures"
    bl_options = {"REGISTER", "UNDO"}

    budget: bpy.props.EnumProperty(name="Texel budget", items=[
        ("AUTO", "As the input", "As many texels as the input's texture uses"),
        ("SIZE", "Texture size", "A square texture of this side"),
        ("TEXELS", "Texels", "This many million texels")], default="AUTO")
    size: bpy.props.IntProperty(name="Size", default=2048, min=16, max=16384)
    megatexels: bpy.props.FloatProperty(name="Megatexels", default=4.0, min=0.001, max=256.0)
    map: bpy.props.EnumProperty(name="Map", items=[
        ("DETAIL", "Detail", "Texels where the texture has detail"),
        ("AREA", "Area", "The same texels per unit of surface area"),
        ("TEXEL", "Texel", "The input's own texel density"),
        ("HARMONIC", "Harmonic", "The harmonic map exactly")], default="DETAIL")
    page_size: bpy.props.IntProperty(name="Page size", description="Largest side of one texture (0: no cap)", default=4096, min=0,
                                     max=16384)
    image_format: bpy.props.EnumProperty(name="Format", items=[("PNG", "PNG", "Lossless"), ("JPEG", "JPEG", "Lossy")], default="PNG")
    quality: bpy.props.IntProperty(name="Quality", description="JPEG quality (PNG: compression)", default=90, min=1, max=100)
    old_uv: bpy.props.EnumProperty(name="Old UV map", items=[("KEEP", "Keep", ""), ("REMOVE", "Remove", "")], default="KEEP")
    old_data: bpy.props.EnumProperty(name="Old materials/images", items=[
        ("KEEP", "Keep", "Keep them in their slots"),
        ("REMOVE", "Remove unused", "Remove the slots no face uses and the materials and images no one uses")], default="KEEP")
    write_report: bpy.props.BoolProperty(name="Write report.html", default=False)
    report_path: bpy.props.StringProperty(name="Report", subtype="FILE_PATH", default="//tightex_report.html")

    @classmethod
    def poll(cls, context):
        return any(o.type == "MESH" for o in context.selected_objects)

    def settings(self, context):
        s = {name: getattr(self, name) for name in SETTINGS}
        s["format"] = s.pop("image_format")
        s["report"] = s.pop("write_report")
        addon = context.preferences.addons.get(__package__)
        s["beside"] = bool(addon and addon.preferences.images_beside)
        return s

    def _finish(self, figures, warnings):
        for line in warnings:
            self.report({"WARNING"}, line)
        for line in run.summary(figures):
            self.report({"INFO"}, line)

    def execute(self, context):
        tightex, error = library.load()
        if tightex is None:
            self.report({"ERROR"}, error)
            return {"CANCELLED"}
        _object_mode(context)
        try:
            figures, warnings = run.tighten(context.selected_objects, self.settings(context))
        except (tightex.Error, ValueError, RuntimeError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self._finish(figures, warnings)
        return {"FINISHED"}

    def invoke(self, context, event):
        tightex, error = library.load()
        if tightex is None:
            self.report({"ERROR"}, error)
            return {"CANCELLED"}
        if context.window is None or bpy.app.background:
            return self.execute(context)
        _object_mode(context)
        self._jobs, messages = run.gather_jobs(context.selected_objects)
        for line in messages:
            self.report({"WARNING"}, line)
        if not self._jobs:
            return {"CANCELLED"}
        self._state = {"job": 0, "stage": "start", "fraction": 0.0, "cancel": False, "error": None, "done": False}
        self._settings = self.settings(context)
        self._thread = threading.Thread(target=self._work, daemon=True)
        self._thread.start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _work(self):
        """The worker thread: tightex on every job; the state tells the modal handler how far it is."""
        state = self._state

        def progress(i, stage, fraction):
            state.update(job=i, stage=stage, fraction=fraction)
            return not state["cancel"]
        try:
            run.compute(self._jobs, self._settings, progress)
        except Exception as e:  # tightex.Cancelled included: reported on the main thread
            state["error"] = e
        state["done"] = True

    def _end(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        state = self._state
        if event.type == "ESC" and not state["cancel"]:
            state["cancel"] = True
        if event.type != "TIMER" and not state["done"]:
            return {"RUNNING_MODAL"}
        if not state["done"]:
            n = len(self._jobs)
            done = (state["job"] + state["fraction"]) / n
            context.window_manager.progress_update(int(1000 * done))
            name = self._jobs[state["job"]].object_name
            context.workspace.status_text_set(f"tightex: {name} ({state['job'] + 1}/{n}): {state['stage']} "
                                              f"{100 * state['fraction']:.0f}%" + ("  (cancelling)" if state["cancel"] else "  Esc: cancel"))
            return {"RUNNING_MODAL"}
        self._end(context)
        if state["cancel"] or state["error"] is not None:
            if state["cancel"]:
                self.report({"WARNING"}, "tightex: cancelled; nothing was changed")
            else:
                self.report({"ERROR"}, f"tightex: {state['error']}")
            return {"CANCELLED"}
        figures, warnings = run.apply_jobs(self._jobs, self._settings)
        self._finish(figures, warnings)
        return {"FINISHED"}


classes = (TIGHTEX_OT_tighten_textures,)
