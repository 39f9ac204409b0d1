"""An object's mesh, UV map, materials and image pixels read from Blender into the arrays that
tightex.optimize_arrays takes. Reads only: nothing of the .blend is changed here."""

import numpy as np

from . import nodes


class Job:
    """One mesh's input to tightex and what is needed to write its result back."""

    def __init__(self, obj):
        self.object_name = obj.name
        self.mesh_name = obj.data.name
        self.arrays = {}             # the keyword arguments of optimize_arrays
        self.loop_triangles = None   # (F, 3) the loops of each triangle
        self.polygon_of = None       # (F,) the polygon of each triangle
        self.roles = []              # per material slot: {slot: [image node names]}
        self.slot_images = []        # per material slot: {slot: input image index}
        self.image_names = []        # input image index -> bpy image name
        self.image_colour = []       # input image index -> whether it holds colour
        self.coloured = False        # baked from the vertex colours
        self.result = None           # optimize_arrays' dict, once run


def _mesh_arrays(mesh):
    """Positions (V, 3), triangles' vertices and loops (F, 3), their polygons (F,), material indices (F,)."""
    mesh.calc_loop_triangles()
    tris = mesh.loop_triangles
    n = len(tris)
    positions = np.empty(len(mesh.vertices) * 3, np.float64)
    mesh.vertices.foreach_get("co", positions)
    verts = np.empty(n * 3, np.int64)
    tris.foreach_get("vertices", verts)
    loops = np.empty(n * 3, np.int64)
    tris.foreach_get("loops", loops)
    polys = np.empty(n, np.int64)
    tris.foreach_get("polygon_index", polys)
    mats = np.empty(n, np.int64)
    tris.foreach_get("material_index", mats)
    return positions.reshape(-1, 3), verts.reshape(-1, 3), loops.reshape(-1, 3), polys, mats


def uv_array(uv_layer):
    """The (L, 2) texture coordinates of a UV map, one per loop."""
    uvs = np.empty(len(uv_layer.data) * 2, np.float64)
    uv_layer.data.foreach_get("uv", uvs)
    return uvs.reshape(-1, 2)


def _srgb_encode(linear):
    linear = np.clip(linear, 0.0, 1.0)
    return np.where(linear <= 0.0031308, linear * 12.92, 1.055 * np.power(linear, 1 / 2.4) - 0.055)


def image_pixels(image, colour):
    """The image as an H x W x 4 uint8 array, row 0 at the top (v = 1), as tightex takes it: a byte
    image's values as stored (sRGB or data, as glTF stores them), a float image's linear values
    sRGB-encoded where it holds colour."""
    w, h = image.size
    if w == 0 or h == 0:
        raise ValueError(f"image '{image.name}' has no pixels (file missing: {image.filepath!r})")
    c = image.channels
    values = np.empty(w * h * c, np.float32)
    image.pixels.foreach_get(values)
    values = values.reshape(h, w, c)
    if c < 4:
        values = np.concatenate([values[:, :, :3] if c >= 3 else np.repeat(values[:, :, :1], 3, 2),
                                 np.ones((h, w, 1), np.float32)], axis=2)
    if image.is_float and colour:
        values[:, :, :3] = _srgb_encode(values[:, :, :3])
    return np.ascontiguousarray((np.clip(values, 0, 1) * 255 + 0.5).astype(np.uint8)[::-1])


def _material_kd(material):
    """The linear base colour of an untextured material (white where its colour comes through nodes: a
    texture's factor stays in the material copy's nodes)."""
    bsdf = nodes.principled(material)
    if bsdf is not None:
        socket = bsdf.inputs["Base Color"]
        return (1.0, 1.0, 1.0) if socket.is_linked else tuple(socket.default_value[:3])
    return tuple(material.diffuse_color[:3]) if material is not None else (1.0, 1.0, 1.0)


def _read_materials(obj, job, used):
    """The materials as optimize_arrays takes them, the images of those some face uses (`used`) read once
    each (a slot no face uses, as the one a previous run left, counts no texels)."""
    images, index = [], {}
    materials = []
    for i, slot in enumerate(obj.material_slots):
        roles = nodes.material_roles(slot.material) if i in used else {}
        entry = {"texture": -1, "kd": _material_kd(slot.material), "maps": {}}
        names, slots = {}, {}
        for role, role_nodes in roles.items():
            image = role_nodes[0].image
            colour = role in ("base", "emissive", "specular") and nodes.is_colour(image)
            key = (image.name, colour)
            if key not in index:
                index[key] = len(images)
                images.append(image_pixels(image, colour))
                job.image_names.append(image.name)
                job.image_colour.append(colour)
            if role == "base":
                entry["texture"] = index[key]
            else:
                entry["maps"][role] = index[key]
            names[role] = [n.name for n in role_nodes]
            slots[role] = index[key]
        materials.append(entry)
        job.roles.append(names)
        job.slot_images.append(slots)
    return images, materials


def _corner_colours(mesh, loops, verts):
    """(F, 3, 4) sRGB corner colours of the mesh's active colour attribute, or None."""
    attr = getattr(mesh, "color_attributes", None)
    attr = attr.active_color if attr is not None else None
    if attr is None or attr.domain not in ("CORNER", "POINT"):
        return None
    values = np.empty(len(attr.data) * 4, np.float32)
    attr.data.foreach_get("color_srgb" if hasattr(attr.data[0], "color_srgb") else "color", values)
    values = values.reshape(-1, 4)
    return np.ascontiguousarray(values[loops if attr.domain == "CORNER" else verts])


def gather(obj):
    """The Job of a mesh object: raises ValueError with a one-line reason where it cannot be run."""
    mesh = obj.data
    if mesh.uv_layers.active is None and not getattr(mesh, "color_attributes", None):
        raise ValueError(f"{obj.name}: no UV map and no colour attribute")
    job = Job(obj)
    positions, verts, loops, polys, mats = _mesh_arrays(mesh)
    if len(verts) == 0:
        raise ValueError(f"{obj.name}: no faces")
    images, materials = _read_materials(obj, job, set(np.unique(mats).tolist()))
    colours = None
    if not any(m["texture"] >= 0 or m["maps"] for m in materials):
        colours = _corner_colours(mesh, loops, verts)
        job.coloured = colours is not None
    if mesh.uv_layers.active is None:
        if images:
            raise ValueError(f"{obj.name}: its materials have image textures but it has no UV map")
        uvs = np.zeros((len(mesh.loops), 2))
    else:
        uvs = uv_array(mesh.uv_layers.active)
    if not materials:
        materials = [{"texture": -1, "kd": (1.0, 1.0, 1.0), "maps": {}}]
        job.roles, job.slot_images = [{}], [{}]
    mats = np.clip(mats, 0, len(materials) - 1)
    job.arrays = dict(positions=positions, faces=verts, uvs=uvs, face_uvs=loops, images=images, materials=materials,
                      material_ids=mats, colors=colours)
    job.loop_triangles, job.polygon_of = loops, polys
    return job
