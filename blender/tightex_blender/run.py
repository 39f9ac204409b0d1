"""The add-on's work without its UI: the jobs gathered from the selected objects, tightex run on them
(on any thread), the results written back. The operator and the headless test both use these."""

import json
import os
import time

import bpy
import numpy as np

from . import apply as write
from . import gather, library

FIGURES_KEY = "tightex_figures"


def mesh_objects(objects):
    """The mesh objects among `objects`, each mesh once (linked duplicates share their result)."""
    seen, out = set(), []
    for obj in objects:
        if obj.type == "MESH" and obj.data.name not in seen:
            seen.add(obj.data.name)
            out.append(obj)
    return out


def gather_jobs(objects):
    """(jobs, messages): one Job per mesh object that can be run, a one-line reason for each other."""
    jobs, messages = [], []
    for obj in mesh_objects(objects):
        try:
            jobs.append(gather.gather(obj))
        except ValueError as e:
            messages.append(str(e))
    return jobs, messages


def options_of(settings):
    """tightex.Options from the operator's settings (a dict of its properties)."""
    tightex, error = library.load()
    if tightex is None:
        raise RuntimeError(error)
    options = tightex.Options()
    if settings.get("budget") == "SIZE":
        options.size = int(settings["size"])
    elif settings.get("budget") == "TEXELS":
        options.texels = float(settings["megatexels"]) * 1e6
    options.map = settings.get("map", "DETAIL").lower()
    options.max_page_side = int(settings.get("page_size", 4096))
    return options


def compute(jobs, settings, progress=None):
    """Runs tightex on each job (callable from a worker thread: tightex releases the GIL). `progress(i,
    stage, fraction)` is called with the job's index; returning False cancels (tightex.Cancelled)."""
    tightex, error = library.load()
    if tightex is None:
        raise RuntimeError(error)
    options = options_of(settings)
    for i, job in enumerate(jobs):
        callback = None if progress is None else (lambda stage, fraction, i=i: progress(i, stage, fraction))
        start = time.monotonic()
        job.result = tightex.optimize_arrays(**job.arrays, options=options, progress=callback, html=bool(settings.get("report")))
        job.seconds = time.monotonic() - start


def figures_of(job):
    """The figures of one job's run, as the panel and the info area show them."""
    report = job.result["report"]
    whole = report.to_dict()
    return {"object": job.object_name, "charts": report.charts, "components": report.components,
            "texels_used": report.output_texels_used, "input_texels_used": report.input_texels_used,
            "surface_psnr_db": report.surface_psnr_db, "seconds": round(job.seconds, 2),
            "texture_sizes": [list(s) for s in report.texture_sizes],
            "already_tight": bool(whole.get("preparation", {}).get("already_tight", False)),
            "warnings": list(report.warnings)}


def _image_folder(settings):
    """The folder beside the saved .blend the new images are kept in (the preference), else None: packed."""
    if settings.get("beside") and bpy.data.filepath:
        folder = os.path.join(os.path.dirname(bpy.data.filepath), "tightex_textures")
        os.makedirs(folder, exist_ok=True)
        return folder
    return None


def _drop_unused(mesh, old_materials):
    """Material slots no polygon uses removed, then those materials and their images where unused."""
    used = np.zeros(len(mesh.materials), bool)
    index = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("material_index", index)
    used[np.unique(index[index < len(used)])] = True
    for i in reversed(range(len(mesh.materials))):
        if not used[i]:
            mesh.materials.pop(index=i)
    for material in old_materials:
        if material is None or material.users > 0:
            continue
        images = [n.image for n in material.node_tree.nodes if n.type == "TEX_IMAGE" and n.image] if material.node_tree else []
        bpy.data.materials.remove(material)
        if images:  # an image's user count may hold an extra (runtime) user: no ID naming it is what counts
            for image, users in bpy.data.user_map(subset=set(images)).items():
                if not users and not image.use_fake_user:
                    bpy.data.images.remove(image)


def apply_jobs(jobs, settings):
    """Writes every job's result back (none for an already tight mesh); returns (figures, warnings)."""
    figures, warnings = [], []
    for job in jobs:
        obj = bpy.data.objects[job.object_name]
        f = figures_of(job)
        figures.append(f)
        warnings += [f"{job.object_name}: {w}" for w in f["warnings"]]
        if f["already_tight"]:
            continue
        old_uv = obj.data.uv_layers.active
        old_uv_name = old_uv.name if old_uv else None
        old_materials = [s.material for s in obj.material_slots]
        warnings += write.apply(obj, job, settings, _image_folder(settings))
        if settings.get("old_uv") == "REMOVE" and old_uv_name and old_uv_name != write.UV_MAP_NAME:
            obj.data.uv_layers.remove(obj.data.uv_layers[old_uv_name])
        if settings.get("old_data") == "REMOVE":
            _drop_unused(obj.data, old_materials)
        if settings.get("report"):
            path = bpy.path.abspath(settings.get("report_path") or "//tightex_report.html")
            if len(jobs) > 1:
                path = path.replace(".html", f"_{bpy.path.clean_name(job.object_name)}.html")
            with open(path, "w", encoding="utf-8") as f_out:
                f_out.write(job.result["report_html"])
            f["report_html"] = path
    bpy.context.scene[FIGURES_KEY] = json.dumps(figures)
    return figures, warnings


def summary(figures):
    """One line per object for the info area."""
    lines = []
    for f in figures:
        if f["already_tight"]:
            lines.append(f"{f['object']}: already tight ({f['charts']} charts, {100 * f['texels_used']:.1f}% of texels used): left as it is")
        else:
            lines.append(f"{f['object']}: {f['charts']} charts, {100 * f['texels_used']:.1f}% of texels used "
                         f"(was {100 * f['input_texels_used']:.1f}%), surface PSNR {f['surface_psnr_db']:.2f} dB, {f['seconds']:.1f} s")
    return lines


def tighten(objects, settings, progress=None):
    """The whole run, synchronous: (figures, warnings). Raises tightex.Cancelled (nothing changed) or
    tightex.Error / RuntimeError / ValueError (nothing changed either)."""
    jobs, messages = gather_jobs(objects)
    if not jobs:
        raise ValueError("; ".join(messages) or "no mesh object selected")
    compute(jobs, settings, progress)
    figures, warnings = apply_jobs(jobs, settings)
    return figures, messages + warnings
