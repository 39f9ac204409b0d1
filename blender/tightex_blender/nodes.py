"""Which image textures of a material feed which of tightex's material slots.

A material's Principled BSDF is read as the glTF importer sets it up: base colour (its image's alpha as
the alpha), metallic and roughness through Separate RGB/XYZ (one image: "metallic_roughness"), normal
through a tangent-space Normal Map node, emission, and occlusion through the "glTF Settings" /
"glTF Material Output" group. Image nodes with no such role ride on a free slot of the same encoding,
so every image the material samples through the active UV map is re-baked.
"""

COLOUR_SLOTS = ("emissive", "specular")
DATA_SLOTS = ("metallic_roughness", "occlusion", "roughness", "metallic", "bump")


def _upstream_images(socket, depth=0):
    """The image texture nodes that feed `socket`, through any chain of at most 5 nodes."""
    found = []
    if depth > 5 or not socket.is_linked:
        return found
    for link in socket.links:
        node = link.from_node
        if node.type == "TEX_IMAGE":
            if node.image is not None and node not in found:
                found.append(node)
            continue
        for sub in node.inputs:
            for image_node in _upstream_images(sub, depth + 1):
                if image_node not in found:
                    found.append(image_node)
    return found


def principled(material):
    """The material's Principled BSDF (the one the active output shows, else the first), or None."""
    if material is None or not material.use_nodes or material.node_tree is None:
        return None
    nodes = material.node_tree.nodes
    for node in nodes:
        if node.type == "OUTPUT_MATERIAL" and node.is_active_output:
            for image in _linked_nodes(node.inputs["Surface"]):
                if image.type == "BSDF_PRINCIPLED":
                    return image
    return next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)


def _linked_nodes(socket):
    return [link.from_node for link in socket.links] if socket.is_linked else []


def _occlusion_images(material):
    for node in material.node_tree.nodes:
        if node.type == "GROUP" and node.node_tree is not None and "glTF" in node.node_tree.name:
            socket = node.inputs.get("Occlusion")
            if socket is not None:
                return _upstream_images(socket)
    return []


def _normal_images(bsdf):
    """(tangent-space normal map images, height images) feeding the BSDF's normal."""
    normal, height = [], []
    for node in _linked_nodes(bsdf.inputs["Normal"]):
        if node.type == "NORMAL_MAP" and node.space == "TANGENT":
            normal += _upstream_images(node.inputs["Color"])
        elif node.type == "BUMP":
            height += _upstream_images(node.inputs["Height"])
    return normal, height


def is_colour(image):
    """Whether the image holds colour (its colour space is not a data one)."""
    return image.colorspace_settings.name not in ("Non-Color", "Raw", "Linear", "XYZ")


def material_roles(material):
    """{slot: [image nodes]} of a material: "base" for the base colour, tightex's slot names for the
    others. Empty for a material without nodes or images."""
    bsdf = principled(material)
    roles = {}
    if bsdf is None:
        return roles

    def put(slot, nodes):
        nodes = [n for n in nodes if not any(n in v for v in roles.values())]
        nodes = [n for n in nodes if n.image == nodes[0].image]  # a second image: carried below
        if nodes and slot not in roles:
            roles[slot] = nodes

    put("base", _upstream_images(bsdf.inputs["Base Color"]))
    metallic, roughness = _upstream_images(bsdf.inputs["Metallic"]), _upstream_images(bsdf.inputs["Roughness"])
    if metallic and roughness and metallic[0].image == roughness[0].image:
        put("metallic_roughness", metallic + [n for n in roughness if n not in metallic])
    else:
        put("metallic", metallic)
        put("roughness", roughness)
    normal, height = _normal_images(bsdf)
    put("normal", normal)
    put("bump", height)
    put("emissive", _upstream_images(bsdf.inputs["Emission"]))
    put("occlusion", _occlusion_images(material))
    put("alpha", _upstream_images(bsdf.inputs["Alpha"]))
    _carry_the_rest(material, roles)
    return roles


def _carry_the_rest(material, roles):
    """Image nodes of no known role (and a separate alpha image) on free slots of their encoding."""
    rest = [n for n in material.node_tree.nodes if n.type == "TEX_IMAGE" and n.image is not None
            and not any(n in v for s, v in roles.items() if s != "alpha")]
    roles.pop("alpha", None)
    for node in rest:
        same = next((s for s, v in roles.items() if v[0].image == node.image), None)
        if same is not None:
            roles[same].append(node)
            continue
        free = [s for s in (COLOUR_SLOTS if is_colour(node.image) else DATA_SLOTS) if s not in roles]
        if free:
            roles[free[0]] = [node]
