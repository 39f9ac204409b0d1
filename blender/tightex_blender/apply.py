"""tightex's result written back into Blender: a new UV map made active, new images, material copies
whose image nodes show them, the faces given those materials. The geometry is not touched."""

import os
import shutil
import tempfile

import bpy
import numpy as np

from . import nodes

UV_MAP_NAME = "tightex"


def _output_loops(job):
    """(F, 3) the loop of each corner of each output triangle (each output triangle is an input one,
    maybe rotated)."""
    out = job.result
    inputs = out["input_triangles"]
    in_verts = job.arrays["faces"][inputs]
    match = out["faces"][:, :, None] == in_verts[:, None, :]
    corner = np.argmax(match, axis=2)
    return np.take_along_axis(job.loop_triangles[inputs], corner, axis=1)


def write_uv_map(mesh, job):
    """A new UV map with the output's coordinates, made active (and the one renders use); returns the
    number of polygons a seam runs through (their loops would need two coordinates)."""
    loops = _output_loops(job).reshape(-1)
    uvs = job.result["uvs"].reshape(-1, 2)
    layer = mesh.uv_layers.new(name=UV_MAP_NAME, do_init=True)
    if layer is None:
        raise ValueError(f"{mesh.name}: no room for another UV map (Blender holds 8)")
    values = np.empty(len(mesh.loops) * 2, np.float64)
    layer.data.foreach_get("uv", values)
    values = values.reshape(-1, 2)
    values[loops] = uvs
    differs = np.any(np.abs(values[loops] - uvs) > 1e-6, axis=1)
    layer.data.foreach_set("uv", values.reshape(-1).astype(np.float32))
    mesh.uv_layers.active = layer
    layer.active_render = True
    polys = job.polygon_of[job.result["input_triangles"]]
    return len(np.unique(np.repeat(polys, 3)[differs]))


def _save_format(settings):
    return ("JPEG", ".jpg") if settings.get("format") == "JPEG" else ("PNG", ".png")


def new_image(name, pixels, colour, settings, folder, pack):
    """A Blender image of `pixels` (H x W x 4 uint8, row 0 at the top), written as PNG or JPEG into
    `folder`, and packed into the .blend where `pack`."""
    h, w = pixels.shape[:2]
    image = bpy.data.images.new(name, w, h, alpha=True)
    image.colorspace_settings.name = "sRGB" if colour else "Non-Color"
    image.pixels.foreach_set((pixels[::-1].astype(np.float32) / 255.0).reshape(-1))
    file_format, ext = _save_format(settings)
    image.file_format = file_format
    path = os.path.join(folder, bpy.path.clean_name(name) + ext)
    image.filepath_raw = path
    image.save(filepath=path, quality=int(settings.get("quality", 90)))
    image.source = "FILE"
    if not pack:
        image.filepath = bpy.path.relpath(path)
    else:
        image.pack()
        image.filepath = "//" + os.path.basename(path)
    image.reload()
    return image


def _slot_of_output(job, m):
    """The input material slot whose node set-up output material `m` takes: for a new material the one
    most of its faces came from, for a kept one the input material its faces had."""
    faces = job.result["face_materials"] == m
    inputs = job.arrays["material_ids"][job.result["input_triangles"][faces]]
    return int(np.bincount(inputs).argmax()) if len(inputs) else 0


def _base_node(material):
    """A material copy's base colour image node, made where it has none (a vertex-coloured object)."""
    tree = material.node_tree
    bsdf = nodes.principled(material)
    if bsdf is None:
        bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
        out = next((n for n in tree.nodes if n.type == "OUTPUT_MATERIAL"), None) or tree.nodes.new("ShaderNodeOutputMaterial")
        tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    node = tree.nodes.new("ShaderNodeTexImage")
    node.name = "tightex base colour"
    tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    return node


def new_material(obj, job, m, images):
    """The Blender material of output material `m`: a copy of its input material with each image node
    pointed at the new image of its slot."""
    out = job.result["materials"][m]
    slot = _slot_of_output(job, m)
    source = obj.material_slots[slot].material if slot < len(obj.material_slots) else None
    if source is None:
        material = bpy.data.materials.new(obj.name + "_tightex")
        material.use_nodes = True
    else:
        material = source.copy()
        material.name = source.name + "_tightex"
    roles = dict(job.roles[slot]) if slot < len(job.roles) else {}
    wanted = dict(out["maps"])
    if out["texture"] >= 0:
        wanted["base"] = out["texture"]
        if "base" not in roles:
            roles["base"] = [_base_node(material).name]
    for role, image_index in wanted.items():
        for name in roles.get(role, []):
            material.node_tree.nodes[name].image = images[image_index]
    return material


def assign_materials(obj, mesh, job, materials):
    """The polygons given their output material: new ones appended to the mesh's materials, kept ones
    stay on their input slot."""
    index = {}
    for m, material in materials.items():
        mesh.materials.append(material)
        index[m] = len(mesh.materials) - 1
    poly_index = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("material_index", poly_index)
    for m in range(len(job.result["materials"])):
        faces = job.result["face_materials"] == m
        polys = job.polygon_of[job.result["input_triangles"][faces]]
        poly_index[polys] = index[m] if m in index else _slot_of_output(job, m)
    mesh.polygons.foreach_set("material_index", poly_index)


def apply(obj, job, settings, folder=None):
    """Writes the job's result into `obj`'s mesh and the .blend; returns a list of warnings."""
    mesh = obj.data
    out = job.result
    warnings = []
    cut = write_uv_map(mesh, job)
    if cut:
        warnings.append(f"{obj.name}: {cut} polygons have a seam through them (triangulate first for exact texels there)")
    temporary = folder is None
    folder = folder or tempfile.mkdtemp(prefix="tightex_")
    new = [m for m, d in enumerate(out["materials"]) if d.get("new")]
    used = sorted({i for m in new for i in [out["materials"][m]["texture"], *out["materials"][m]["maps"].values()] if i >= 0})
    images = {}
    for i in used:
        colour = _image_is_colour(job, out, i)
        images[i] = new_image(f"{obj.name}_tightex_{len(images)}", out["images"][i], colour, settings, folder, temporary)
    if temporary:
        shutil.rmtree(folder, ignore_errors=True)  # the images are packed
    materials = {m: new_material(obj, job, m, images) for m in new}
    assign_materials(obj, mesh, job, materials)
    return warnings


def _image_is_colour(job, out, i):
    """Whether output image `i` holds colour: a base colour, emissive or specular one of colour input."""
    for d in out["materials"]:
        if d["texture"] == i:
            return True
        for slot, j in d["maps"].items():
            if j == i:
                return slot in ("emissive", "specular")
    return True
