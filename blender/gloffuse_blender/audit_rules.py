# ---------------------------------------------------------------------------
# gloffuse audit_rules.py: the scan of `gloffuse audit`. It walks the nodes a
# material really renders with (upstream of its active Cycles output, through
# Reroutes and muted nodes, into node groups but never into gloffuse's own,
# which are already corrected) and reports each energy problem or unusual
# case as a finding: a plain dict {rule, node, node_type, detail, twin}
# (the audit's shared interface, issue 21). Rust owns the catalogue text and
# the version ranges; the document's "rules" list says which ids apply here.
#
# A module of the gloffuse_blender package, used by the audit job
# (audit_job.py) and its twins (audit_twin.py). Functions and constants only;
# every Blender version difference goes through compat.py.
#
#   applicable_rules(rules) -> set of rule ids that apply in this Blender
#   twin_groups(audit) -> the gloffuse group names a twin may use
#   scan_material(material, rules, groups) -> ([finding, ...], error or None)
#   scan_scenes(rules) -> file findings (filter-glossy)
#   srgb_255(linear), luminance_255(color) -> the PBR rules' sRGB values
#   uv_maps_named(material) -> the UV map names its nodes name
# ---------------------------------------------------------------------------
import math
import os

import bpy

from .compat import filter_glossy_property, is_missing, material_node_tree, principled_input, version_in_range
from .nodes import is_gloffuse_group

# Distributions whose single-scattering lobe loses energy, and what the twin
# puts in place: Multiscatter GGX on the node itself, else a gloffuse group.
SINGLE_SCATTER = ("GGX", "BECKMANN", "ASHIKHMIN_SHIRLEY")
GLOSSY_TYPES = ("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic")
MULTISCATTER_TWIN = "Multiscatter GGX"
CLAMP_TWIN = "clamped to 1"
TOON_TWIN = "Smooth 0"
ADD_TWIN = "itself (a fix scales the Add Shader to 100 % by its brightness)"
# The kinds of lobe a twin replaces (the audit section's twin_names), and the
# generate mode whose groups each kind's twins are.
TWIN_KINDS = {"multiscatter": "multiscatter", "layered": "layered", "anisotropic": "anisotropic",
              "glass": "glass", "refraction": "glass"}

# Nodes that carry no reflecting closure (add-reflecting), and the colour
# inputs that may exceed 1 (light, not albedo: color-above-one).
NOT_REFLECTING = ("ShaderNodeEmission", "ShaderNodeHoldout", "ShaderNodeBackground",
                  "ShaderNodeVolumeAbsorption", "ShaderNodeVolumeScatter",
                  "ShaderNodeVolumePrincipled", "ShaderNodeVolumeInfo")
REFLECTING_EXTRA = ("ShaderNodeSubsurfaceScattering", "ShaderNodeEeveeSpecular")
LIGHT_NODES = NOT_REFLECTING
KNOWN_OTHER_TYPES = ("NodeGroup", "NodeReroute", "NodeFrame", "NodeGroupInput",
                     "NodeGroupOutput", "ShaderNodeGroup")
COLOR_EPSILON = 1e-6


# --- version, document ---------------------------------------------------------

def applicable_rules(rules):
    """The ids of the document's rules whose [from, before) range holds this Blender."""
    return {rule["id"] for rule in rules if version_in_range(rule["from"], rule.get("before"))}


def twin_groups(audit):
    """{kind of lobe: {distribution: twin}}: the twin of each kind of lobe the
    audit replaces, as the audit section names them: a gloffuse group (built
    only when a job asks for it, see audit_job.py's group_needs), or
    MULTISCATTER_TWIN where Blender's own Multiscatter GGX keeps the light. A
    distribution missing has no conserving twin in this Blender."""
    names = audit.get("twin_names") or {}
    return {kind: dict(names.get(kind) or {}) for kind in TWIN_KINDS}


def is_own_group(tree):
    """A gloffuse group as gloffuse built it: already corrected, never scanned
    or flagged. Known by its tag and content (nodes.py's is_gloffuse_group),
    never by its name: a user's group of any name is scanned."""
    return is_gloffuse_group(tree)


# --- sockets and the walk ----------------------------------------------------------

def source(socket):
    """The output socket that feeds input `socket`, looking through Reroutes
    and muted nodes (whose internal links pass a value on); None if unlinked."""
    for _hop in range(1000):  # a bound, not a limit any real tree reaches
        links = [link for link in socket.links if not link.is_muted and link.is_valid]
        if not links:
            return None
        out = links[0].from_socket
        node = out.node
        if node.bl_idname == "NodeReroute":
            socket = node.inputs[0]
        elif node.mute:
            passed = [link.from_socket for link in node.internal_links if link.to_socket == out]
            if not passed:
                return None
            socket = passed[0]
        else:
            return out
    return None


def source_node(socket):
    out = source(socket)
    return None if out is None else out.node


def constant(socket):
    """The socket's own value when nothing feeds it (a float, or [r, g, b]), else None."""
    if source(socket) is not None:
        return None
    value = socket.default_value
    if socket.type == "RGBA":
        return [round(float(c), 6) for c in value[:3]]
    if socket.type == "VALUE":
        return round(float(value), 6)
    return None


def active_output(tree, types=("ShaderNodeOutputMaterial",)):
    """The output Cycles renders: the active one targeting All or Cycles, else any."""
    outputs = [node for node in tree.nodes if node.bl_idname in types]
    for node in outputs:
        if getattr(node, "is_active_output", False) and getattr(node, "target", "ALL") in ("ALL", "CYCLES"):
            return node
    for node in outputs:
        if getattr(node, "target", "ALL") in ("ALL", "CYCLES"):
            return node
    return outputs[0] if outputs else None


def reachable(tree, starts, path, stack=()):
    """(node, path) of every node upstream of the input sockets `starts`,
    depth first, descending into groups (path: the names down to the node)."""
    seen = set()
    todo = list(reversed(starts))
    while todo:
        node = source_node(todo.pop())
        if node is None or node.name in seen:
            continue
        seen.add(node.name)
        node_path = path + [node.name]
        yield node, node_path
        todo.extend(reversed([sock for sock in node.inputs if sock.is_linked]))
        group = getattr(node, "node_tree", None) if node.bl_idname == "ShaderNodeGroup" else None
        if group is not None and not is_own_group(group) and group.name not in stack:
            output = active_output(group, ("NodeGroupOutput",))
            if output is not None:
                yield from reachable(group, list(output.inputs), node_path, stack + (group.name,))


def material_starts(tree):
    output = active_output(tree)
    return output, ([] if output is None else [output.inputs["Surface"], output.inputs["Volume"]])


def resolve_path(tree, path):
    """The node a finding's path addresses below the material, and the chain of
    (group node, tree) it goes through; (None, chain) if it is gone."""
    chain = []
    for name in path[1:-1]:
        node = tree.nodes.get(name)
        if node is None or getattr(node, "node_tree", None) is None:
            return None, chain
        chain.append(node)
        tree = node.node_tree
    return tree.nodes.get(path[-1]), chain


# --- findings --------------------------------------------------------------------

def finding(rule, node, detail, twin=None):
    return {"rule": rule, "node": None, "node_type": node.bl_idname if node is not None else "Material",
            "detail": detail, "twin": twin}


def rough(node, name="Roughness"):
    """A roughness that matters: linked (None) or above 0."""
    value = constant(node.inputs[name])
    return value is None or value > 0.0, value


def multiscatter_twin(distribution, groups):
    if distribution == "GGX":
        return MULTISCATTER_TWIN
    return groups["multiscatter"].get(distribution)


def anisotropic(node):
    """An anisotropic lobe: its Anisotropy linked or not 0 (3.x's Anisotropic
    BSDF, 4.0+'s Glossy BSDF)."""
    return "Anisotropy" in node.inputs and constant(node.inputs["Anisotropy"]) != 0.0


def glossy_detail(node, roughness):
    detail = {"distribution": node.distribution, "roughness": roughness,
              "color": constant(node.inputs["Color"])}
    if "Anisotropy" in node.inputs:
        detail["anisotropy"] = constant(node.inputs["Anisotropy"])
    return detail


def rule_glossy_single_scatter(node, groups):
    if node.bl_idname not in GLOSSY_TYPES or node.distribution not in SINGLE_SCATTER:
        return []
    matters, roughness = rough(node)
    if not matters:
        return []
    if anisotropic(node):
        twin = groups["anisotropic"].get(node.distribution)
    else:
        twin = multiscatter_twin(node.distribution, groups)
    return [finding("glossy-single-scatter", node, glossy_detail(node, roughness), twin)]


def rule_anisotropic_multiscatter(node, groups):
    if node.bl_idname not in GLOSSY_TYPES or node.distribution != "MULTI_GGX" \
            or not anisotropic(node):
        return []
    return [finding("anisotropic-multiscatter", node, glossy_detail(node, constant(node.inputs["Roughness"])),
                    groups["anisotropic"].get("GGX"))]


def rule_microfacet_single_scatter(rule, idname, twin_kind=None):
    """The GGX/Beckmann rules of Metallic, Glass and Refraction BSDF; their twin
    Multiscatter GGX, or the twins of `twin_kind`."""
    def rule_function(node, groups):
        if node.bl_idname != idname or node.distribution not in ("GGX", "BECKMANN"):
            return []
        matters, roughness = rough(node)
        if not matters:
            return []
        detail = {"distribution": node.distribution, "roughness": roughness}
        if "IOR" in node.inputs:
            detail["ior"] = constant(node.inputs["IOR"])
        twin = MULTISCATTER_TWIN if twin_kind is None else groups[twin_kind].get(node.distribution)
        return [finding(rule, node, detail, twin)]
    return rule_function


def principled_detail(node):
    return {"distribution": node.distribution, "roughness": constant(node.inputs["Roughness"]),
            "ior": principled_ior(node), "color": constant(node.inputs["Base Color"])}


def principled_ior(node):
    """The dielectric IOR of the specular layer: 3.x's Specular s (F0 = 0.08 s,
    eta = (1 + sqrt F0) / (1 - sqrt F0); linked: 1.5), 4.0+'s IOR input."""
    specular = principled_input(node, "specular")
    if specular is None:
        return constant(node.inputs["IOR"])
    s = constant(specular)
    if s is None:
        return 1.5
    root = math.sqrt(min(max(0.08 * s, 0.0), 0.99))
    return round((1.0 + root) / (1.0 - root), 6)


def thin_glass_only(node):
    """A Principled BSDF all of whose light goes to its thin-glass lobes (5.2's
    Thin Wall on, Transmission 1, Metallic 0): Cycles compensates those under
    any distribution (bsdf_thin_glass_setup preserves energy whatever the node
    asks), and the lobes that lose under GGX (metal, specular over the base)
    then carry no weight."""
    wall = principled_input(node, "thin_wall")
    if wall is None or source(wall) is not None or not wall.default_value:
        return False
    return constant(principled_input(node, "transmission")) == 1.0 \
        and constant(node.inputs["Metallic"]) == 0.0


def rule_principled_single_scatter(node, groups):
    if node.bl_idname != "ShaderNodeBsdfPrincipled" or node.distribution != "GGX" \
            or thin_glass_only(node):
        return []
    return [finding("principled-single-scatter", node, principled_detail(node), MULTISCATTER_TWIN)]


def principled_without_transmission(node):
    """Transmission and Subsurface both constant 0: the Principled BSDF is a coat
    over a diffuse base mixed with a metal by Metallic, which the Layered group
    and a Multiscatter GGX Glossy model (audit_twin.py)."""
    sockets = [principled_input(node, "transmission"), principled_input(node, "subsurface")]
    return all(sock is None or constant(sock) == 0.0 for sock in sockets)


def rule_principled_creates_energy(node, groups):
    if node.bl_idname != "ShaderNodeBsdfPrincipled":
        return []
    twin = groups["layered"].get("GGX") if principled_without_transmission(node) else None
    item = finding("principled-creates-energy", node, principled_detail(node), twin)
    if twin is not None and constant(node.inputs["Metallic"]) != 0.0:
        # The metal part: gloffuse's Multiscatter group, not Blender's Multiscatter
        # GGX, which before 4.0 renders too bright mixed with another closure.
        item["metal_twin"] = groups["multiscatter"].get("GGX")
    return [item]


def layering_parts(mix):
    """(factor node, diffuse, glossy) of a Mix Shader layering a Glossy over a
    Diffuse by a Fresnel or Layer Weight factor; None for any other Mix."""
    if mix.bl_idname != "ShaderNodeMixShader":
        return None
    factor = source_node(mix.inputs[0])
    if factor is None or factor.bl_idname not in ("ShaderNodeFresnel", "ShaderNodeLayerWeight"):
        return None
    a, b = source_node(mix.inputs[1]), source_node(mix.inputs[2])
    if a is None or b is None:
        return None
    if b.bl_idname == "ShaderNodeBsdfDiffuse":
        a, b = b, a
    if a.bl_idname != "ShaderNodeBsdfDiffuse" or b.bl_idname not in GLOSSY_TYPES:
        return None
    return factor, a, b


def layering_ior(factor):
    """The coat's IOR the factor stands for: Fresnel's IOR (None if linked),
    Layer Weight's 1 / (1 - Blend) when constant, else 1.5."""
    if factor.bl_idname == "ShaderNodeFresnel":
        return constant(factor.inputs["IOR"])
    blend = constant(factor.inputs["Blend"])
    if blend is None:
        return 1.5
    return round(1.0 / max(1.0 - blend, 1e-5), 6)  # Cycles' own floor on 1 - Blend


def layered_twin(distribution, groups):
    layered = groups["layered"]
    return layered.get(distribution) or layered.get("GGX")


def rule_mix_fresnel_layering(node, groups):
    parts = layering_parts(node)
    if parts is None:
        return []
    factor, diffuse, glossy = parts
    detail = {"distribution": glossy.distribution, "roughness": constant(glossy.inputs["Roughness"]),
              "ior": layering_ior(factor), "color": constant(diffuse.inputs["Color"])}
    return [finding("mix-fresnel-layering", node, detail, layered_twin(glossy.distribution, groups))]


def carries_reflection(socket, stack=()):
    """Whether the shader feeding `socket` holds a reflecting closure."""
    node = source_node(socket)
    if node is None or node.bl_idname in NOT_REFLECTING:
        return False
    if node.bl_idname in ("ShaderNodeMixShader", "ShaderNodeAddShader"):
        return any(carries_reflection(sock, stack) for sock in node.inputs if sock.type == "SHADER")
    if node.bl_idname == "ShaderNodeGroup":
        tree = node.node_tree
        if tree is None or tree.name in stack:
            return False
        output = active_output(tree, ("NodeGroupOutput",))
        return output is not None and any(carries_reflection(sock, stack + (tree.name,))
                                          for sock in output.inputs if sock.type == "SHADER")
    return node.bl_idname.startswith("ShaderNodeBsdf") or node.bl_idname in REFLECTING_EXTRA


def feeds_output(node):
    """Whether `node` is what its material's active output renders as the surface
    (through Reroutes and muted nodes)."""
    tree = node.id_data
    tree = getattr(tree, "node_tree", tree)  # some versions give the material itself
    output = active_output(tree)
    return output is not None and source_node(output.inputs["Surface"]) == node


def rule_add_reflecting(node, groups):
    if node.bl_idname != "ShaderNodeAddShader":
        return []
    if not (carries_reflection(node.inputs[0]) and carries_reflection(node.inputs[1])):
        return []
    return [finding("add-reflecting", node, {"feeds_output": feeds_output(node)}, ADD_TWIN)]


def is_surface_shader(node):
    """A BSDF-like node whose colours are albedos (not a light, not a mixer)."""
    return node.bl_idname not in LIGHT_NODES and node.bl_idname not in (
        "ShaderNodeMixShader", "ShaderNodeAddShader", "ShaderNodeGroup") \
        and any(sock.type == "SHADER" for sock in node.outputs)


def rule_color_above_one(node, groups):
    if not is_surface_shader(node):
        return []
    found = []
    for sock in node.inputs:
        if sock.type != "RGBA" or not getattr(sock, "enabled", True) or sock.name.startswith("Emission"):
            continue
        color = constant(sock)
        if color is not None and max(color) > 1.0 + COLOR_EPSILON:
            found.append(finding("color-above-one", node, {"input": sock.identifier, "color": color},
                                 CLAMP_TWIN))
    return found


def rule_toon_smooth(node, groups):
    if node.bl_idname != "ShaderNodeBsdfToon":
        return []
    matters, smooth = rough(node, "Smooth")
    return [finding("toon-smooth", node, {"value": smooth}, TOON_TWIN)] if matters else []


def image_file_missing(image):
    if image.packed_file is not None or image.source not in ("FILE", "SEQUENCE", "TILED"):
        return None
    path = os.path.normpath(bpy.path.abspath(image.filepath, library=image.library))
    if image.source == "TILED":
        candidates = [path.replace("<UDIM>", str(tile.number)) for tile in image.tiles] or [path]
    else:
        candidates = [path]
    return None if any(os.path.isfile(p) for p in candidates) else path


def rule_missing_texture(node, groups):
    if node.bl_idname not in ("ShaderNodeTexImage", "ShaderNodeTexEnvironment") or node.image is None:
        return []
    path = image_file_missing(node.image)
    if path is None:
        return []
    return [finding("missing-texture", node, {"image": node.image.name, "path": path})]


def rule_linked_group(node, groups):
    tree = getattr(node, "node_tree", None) if node.bl_idname == "ShaderNodeGroup" else None
    if tree is None or tree.library is None:
        return []
    return [finding("linked-library", node, {"library": tree.library.filepath,
                                             "missing": is_missing(tree.library)})]


def rule_emission(node, groups):
    if node.bl_idname == "ShaderNodeEmission":
        return [finding("emission", node, {"color": constant(node.inputs["Color"]),
                                           "value": constant(node.inputs["Strength"])})]
    if node.bl_idname != "ShaderNodeBsdfPrincipled":
        return []
    strength = constant(node.inputs["Emission Strength"])
    color = constant(principled_input(node, "emission_color"))
    if (strength is None or strength > 0.0) and (color is None or max(color) > 0.0):
        return [finding("emission", node, {"color": color, "value": strength})]
    return []


def rule_holdout(node, groups):
    return [finding("holdout", node, {})] if node.bl_idname == "ShaderNodeHoldout" else []


# What a material may read that the furnace's sphere cannot know: the data of
# a specific mesh, the object it is on and where, the scene around it.
SCENE_INPUTS = {
    "ShaderNodeAttribute": "a mesh or object attribute",
    "ShaderNodeVertexColor": "a colour attribute of the mesh",
    "ShaderNodeObjectInfo": "the object (its location, colour, index or random value)",
    "ShaderNodeParticleInfo": "particles",
    "ShaderNodeHairInfo": "hair curves",
    "ShaderNodePointInfo": "a point cloud",
    "ShaderNodeWireframe": "the mesh's edges",
    "ShaderNodeBevel": "the mesh's edges",
    "ShaderNodeAmbientOcclusion": "the geometry around it",
    "ShaderNodeShaderToRGB": "the scene's lights",
    "ShaderNodeCameraData": "the camera",
}
POSITION_OUTPUTS = {("ShaderNodeNewGeometry", "Position"): "its place in the world",
                    ("ShaderNodeTexCoord", "Object"): "another object's place",
                    ("ShaderNodeTexCoord", "Camera"): "the camera",
                    ("ShaderNodeTexCoord", "Window"): "the camera"}


def scene_input(node):
    """What `node` lets the material depend on beyond its shader, or None."""
    what = SCENE_INPUTS.get(node.bl_idname)
    if what is not None:
        return what
    for output in node.outputs:
        what = POSITION_OUTPUTS.get((node.bl_idname, output.name))
        if what is None or not output.is_linked:
            continue
        if (node.bl_idname, output.name) == ("ShaderNodeTexCoord", "Object") \
                and getattr(node, "object", None) is None:
            continue  # its own object's coordinates: the sphere's
        return what
    return None


def rule_depends_on_scene(node, groups):
    what = scene_input(node)
    if what is None:
        return []
    detail = {"reads": what}
    for key in ("attribute_name", "layer_name"):
        if getattr(node, key, ""):
            detail["name"] = getattr(node, key)
    return [finding("depends-on-scene", node, detail)]


# --- PBR ranges (issue 41): plausible albedos, read off constant colours ----------
# Socket colours are scene-linear; the charts the rules cite are in 8-bit sRGB.
# Unity's Material Validator compares the luminance (Rec. 709 weights on the
# linear colour, then encoded); Substance's PBR Validate compares each channel.
# Bounds are 0..255 sRGB values, not rounded: a value at a bound passes.
UNITY_NON_METAL = (50.0, 243.0)
UNITY_METAL_FLOOR = 186.0
SUBSTANCE_DARK_STRICT = 30.0
SUBSTANCE_DARK_RECOMMENDED = 50.0
SUBSTANCE_METAL_FLOOR = 0.6 * 255.0  # 60 % reflectance, as a share of the sRGB value
METAL_FROM = 0.9  # Metallic at or above: a metal
NON_METAL_UP_TO = 0.1  # Metallic at or below: a non-metal; in between: neither


def srgb_255(linear):
    """A linear channel as an sRGB value in 0..255 (the standard transfer function
    with its linear segment below 0.0031308); not rounded."""
    c = max(float(linear), 0.0)
    encoded = 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1.0 / 2.4) - 0.055
    return 255.0 * encoded


def luminance_255(color):
    """The colour's luminance (Rec. 709 weights on the linear channels) in sRGB 0..255."""
    return srgb_255(0.2126729 * color[0] + 0.7151522 * color[1] + 0.0721750 * color[2])


def constant_color(socket):
    """The socket's colour when it is constant: its own value, or an RGB node's
    (through Reroutes and muted nodes); None when anything else feeds it."""
    out = source(socket)
    if out is None:
        return constant(socket)
    if out.node.bl_idname == "ShaderNodeRGB":
        return [round(float(c), 6) for c in out.default_value[:3]]
    return None


def pbr_colors(node):
    """(input name, linear colour, "metal" or "non-metal", Metallic) of each colour
    of `node` the PBR rules judge: a Principled BSDF's Base Color by its constant
    Metallic (none while Transmission is not constant 0: a glass's colour is its
    tint), a Diffuse BSDF's Color (a non-metal), a Glossy BSDF's Color (a metal's
    reflectance)."""
    idname = node.bl_idname
    if idname == "ShaderNodeBsdfDiffuse":
        found = [("Color", "non-metal", None)]
    elif idname in GLOSSY_TYPES:
        found = [("Color", "metal", None)]
    elif idname == "ShaderNodeBsdfPrincipled":
        transmission = principled_input(node, "transmission")
        metallic = constant(node.inputs["Metallic"])
        if (transmission is not None and constant(transmission) != 0.0) or metallic is None:
            return []
        kind = "metal" if metallic >= METAL_FROM else "non-metal" if metallic <= NON_METAL_UP_TO else None
        found = [("Base Color", kind, metallic)] if kind else []
    else:
        return []
    colors = []
    for name, kind, metallic in found:
        color = constant_color(node.inputs[name])
        if color is not None:
            colors.append((name, color, kind, metallic))
    return colors


def pbr_detail(name, color, kind, metallic):
    detail = {"input": name, "color": color, "kind": kind,
              "srgb": [round(srgb_255(c), 2) for c in color], "luminance": round(luminance_255(color), 2)}
    if metallic is not None:
        detail["metallic"] = metallic
    return detail


def rule_pbr_albedo_range(node, groups):
    """Unity's charts: a non-metal's luminance within 50..243 sRGB, a metal's at least 186."""
    found = []
    for name, color, kind, metallic in pbr_colors(node):
        lum = luminance_255(color)
        low, high = UNITY_NON_METAL if kind == "non-metal" else (UNITY_METAL_FLOOR, math.inf)
        if lum < low or lum > high:
            found.append(finding("pbr-albedo-range", node, pbr_detail(name, color, kind, metallic)))
    return found


def rule_pbr_dark_albedo(node, groups):
    """Substance's dark floor: each channel of a non-metal's colour at least 50 sRGB
    (recommended), 30 (strict; `strict` in the detail when below it)."""
    found = []
    for name, color, kind, metallic in pbr_colors(node):
        darkest = min(srgb_255(c) for c in color)
        if kind == "non-metal" and darkest < SUBSTANCE_DARK_RECOMMENDED:
            detail = pbr_detail(name, color, kind, metallic)
            detail["strict"] = darkest < SUBSTANCE_DARK_STRICT
            found.append(finding("pbr-dark-albedo", node, detail))
    return found


def rule_pbr_metal_reflectance(node, groups):
    """Substance's metal reflectance: each channel of a metal's colour at least 60 %."""
    found = []
    for name, color, kind, metallic in pbr_colors(node):
        if kind == "metal" and min(srgb_255(c) for c in color) < SUBSTANCE_METAL_FLOOR:
            found.append(finding("pbr-metal-reflectance", node, pbr_detail(name, color, kind, metallic)))
    return found


UV_MAP_NODES = (("ShaderNodeUVMap", "uv_map"), ("ShaderNodeNormalMap", "uv_map"),
                ("ShaderNodeTangent", "uv_map"))


def uv_maps_named(material, stack=()):
    """The UV map names the nodes of `material` (or of a node group, nested
    groups included) name: UV Map, Normal Map, Tangent."""
    tree = material if isinstance(material, bpy.types.NodeTree) else material_node_tree(material)
    names = set()
    if tree is None or tree.name in stack:
        return names
    for node in tree.nodes:
        for idname, key in UV_MAP_NODES:
            if node.bl_idname == idname and getattr(node, key, ""):
                names.add(getattr(node, key))
        group = getattr(node, "node_tree", None) if node.bl_idname == "ShaderNodeGroup" else None
        if group is not None:
            names |= uv_maps_named(group, stack + (tree.name,))
    return names


def rule_unknown_node(node, groups):
    idname = node.bl_idname
    no_tree = idname == "ShaderNodeGroup" and node.node_tree is None
    custom = not idname.startswith("ShaderNode") and idname not in KNOWN_OTHER_TYPES
    if idname == "ShaderNodeScript" or no_tree or custom:
        return [finding("unknown-node", node, {})]
    return []


NODE_RULES = (
    rule_glossy_single_scatter,
    rule_anisotropic_multiscatter,
    rule_microfacet_single_scatter("metallic-single-scatter", "ShaderNodeBsdfMetallic"),
    rule_microfacet_single_scatter("glass-single-scatter", "ShaderNodeBsdfGlass", "glass"),
    rule_microfacet_single_scatter("refraction-single-scatter", "ShaderNodeBsdfRefraction", "refraction"),
    rule_principled_creates_energy,  # before single-scatter: its twin replaces the node
    rule_principled_single_scatter,
    rule_mix_fresnel_layering,
    rule_add_reflecting,
    rule_color_above_one,
    rule_toon_smooth,
    rule_missing_texture,
    rule_linked_group,
    rule_emission,
    rule_holdout,
    rule_depends_on_scene,
    rule_unknown_node,
    rule_pbr_albedo_range,
    rule_pbr_dark_albedo,
    rule_pbr_metal_reflectance,
)


# --- materials and scenes ------------------------------------------------------------

def material_level_findings(material, output):
    """Findings on the material itself: linked from a library, a linked Volume."""
    found = []
    if material.library is not None:
        found.append(finding("linked-library", None, {"library": material.library.filepath,
                                                      "missing": is_missing(material.library)}))
        found[-1]["node"] = [material.name]
    if output is not None and source(output.inputs["Volume"]) is not None:
        found.append(finding("volume", output, {}))
        found[-1]["node"] = [material.name, output.name]
    return found


def material_errors(found):
    """The material error the findings amount to (missing texture or library), or None."""
    errors = []
    for item in found:
        detail = item["detail"]
        if item["rule"] == "missing-texture":
            errors.append("missing texture %s (%s)" % (detail["image"], detail["path"]))
        elif item["rule"] == "linked-library" and detail["missing"]:
            errors.append("missing library %s" % detail["library"])
    return "; ".join(errors) or None


def scan_material(material, rules, groups):
    """The findings of the rules in `rules` (ids) on `material`, and its error
    (None when it can be rendered and judged)."""
    tree = material_node_tree(material)
    output, starts = material_starts(tree) if tree is not None else (None, [])
    found = material_level_findings(material, output)
    if tree is not None:
        for node, path in reachable(tree, starts, [material.name]):
            for rule in NODE_RULES:
                for item in rule(node, groups):
                    item["node"] = path
                    found.append(item)
    if is_missing(material) and not any(item["rule"] == "linked-library" for item in found):
        found.append(finding("linked-library", None, {"library": None, "missing": True}))
        found[-1]["node"] = [material.name]
    found = once_per_library(found)
    error = material_errors(found)
    return [item for item in found if item["rule"] in rules], error


def once_per_library(found):
    """The findings with one linked-library finding per library: the groups nested in
    a linked group come from its library too, and would repeat it."""
    seen = set()
    kept = []
    for item in found:
        if item["rule"] == "linked-library":
            if item["detail"]["library"] in seen:
                continue
            seen.add(item["detail"]["library"])
        kept.append(item)
    return kept


def scan_scenes(rules):
    """File findings: every scene with Filter Glossy on."""
    if "filter-glossy" not in rules:
        return []
    found = []
    for scene in bpy.data.scenes:
        value = getattr(scene.cycles, filter_glossy_property(scene.cycles))
        if value > 0.0:
            item = {"rule": "filter-glossy", "node": ["scene", scene.name], "node_type": "Scene",
                    "detail": {"value": round(float(value), 6)}, "twin": None}
            found.append(item)
    return found
