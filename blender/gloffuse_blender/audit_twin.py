# ---------------------------------------------------------------------------
# gloffuse audit_twin.py: what `gloffuse audit` puts in place of a flagged
# node. One finding's replacement applied to a node tree: Multiscatter GGX on
# the node itself, a gloffuse group node in its place (the Multiscatter,
# Layered, Anisotropic, Glass or Refraction group: inputs copied, outputs
# relinked), an Add Shader that creates energy scaled back to 100 % (only in a
# fix, by the scale Rust measured: a twin is rendered before it is known), a
# colour clamped to 1, a Toon's Smooth set to 0. The twin of a material is its
# copy with every replacement
# applied, and its own copies of the group trees on the way to a flagged node
# (so no other material changes); --fix applies the same replacements to the
# real trees in place.
#
# A module of the gloffuse_blender package, used by the audit job
# (audit_job.py). Functions and constants only.
#
#   make_twin(material, findings) -> (twin material or None, replaced)
#   apply_finding(tree, finding, copies=None) -> True if it changed the tree
#   set_aside_groups(names) / restore_groups(kept) -> the file's own groups of those names
#   remove_unused_added(before) -> removes the groups and images this run added and nothing uses
# ---------------------------------------------------------------------------
import bpy

from .audit_rules import MULTISCATTER_TWIN, constant, layering_parts
from .compat import material_node_tree

TWIN_SUFFIX = " (gloffuse twin)"
SET_ASIDE_SUFFIX = " (audit kept)"


# --- sockets ---------------------------------------------------------------------

def live_link(socket):
    links = [link for link in socket.links if not link.is_muted and link.is_valid]
    return links[0] if links else None


def feed(tree, target, socket):
    """Give input `target` what input `socket` has: its link's source, else its value."""
    link = live_link(socket)
    if link is not None:
        tree.links.new(link.from_socket, target)
    elif socket.type == target.type and socket.type in ("RGBA", "VALUE"):
        target.default_value = socket.default_value


def group_node(tree, group, location):
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    node.location = location
    return node


def shader_output(node):
    return next(s for s in node.outputs if s.type == "SHADER")


def replace_node(tree, old, new):
    """Put `new` where `old` was: location, parent, outgoing shader links, name."""
    new.location = old.location
    new.parent = old.parent
    shader_out = shader_output(new)
    for out in old.outputs:
        for link in list(out.links):
            if out.type == "SHADER":
                tree.links.new(shader_out, link.to_socket)
    name = old.name
    tree.nodes.remove(old)
    new.name = name  # keeps later findings' paths addressing it


def group_in_place(tree, old, group_name, inputs, values=None):
    """A group node of the gloffuse group `group_name` in place of `old`;
    inputs: {group input: socket of the old tree to copy}, values: {input: value}."""
    group = bpy.data.node_groups.get(group_name)
    if group is None:
        return False
    node = group_node(tree, group, old.location)
    for name, value in (values or {}).items():
        node.inputs[name].default_value = value
    for name, socket in inputs.items():
        if name in node.inputs and socket is not None:
            feed(tree, node.inputs[name], socket)
    replace_node(tree, old, node)
    return True


# --- replacements, one per rule ----------------------------------------------------

def to_multiscatter(tree, node, item):
    node.distribution = "MULTI_GGX"
    return True


def twin_in_place(tree, node, item):
    """The node set to Multiscatter GGX, or the twin group in its place fed
    as the node was, input by input of the same name (Color, Roughness,
    Anisotropy, Rotation, IOR, Normal, Tangent: the groups take the node's own
    inputs, an unlinked Tangent meaning the node's default tangent too)."""
    if item["twin"] == MULTISCATTER_TWIN:
        return to_multiscatter(tree, node, item)
    inputs = {sock.name: sock for sock in node.inputs if sock.enabled}
    return group_in_place(tree, node, item["twin"], inputs)


def principled_layered_twin(tree, node, item):
    """The Layered group for a Principled BSDF before 4.0; where it is partly
    metallic, a Mix Shader by its Metallic of that group and gloffuse's
    Multiscatter group of its Base Color (both conserve in 3.x, as its own lobes
    do not, and as Multiscatter GGX does not in a mix there)."""
    ior = item["detail"].get("ior")
    inputs = {"Base Color": node.inputs["Base Color"], "Roughness": node.inputs["Roughness"],
              "Normal": node.inputs["Normal"]}
    values = {"IOR": 1.5 if ior is None else ior}
    metallic = node.inputs["Metallic"]
    if constant(metallic) == 0.0:
        return group_in_place(tree, node, item["twin"], inputs, values)
    layered_group = bpy.data.node_groups.get(item["twin"])
    metal_group = bpy.data.node_groups.get(item.get("metal_twin") or "")
    if layered_group is None or metal_group is None:
        return False
    layered = group_node(tree, layered_group, (node.location.x - 200, node.location.y))
    layered.inputs["IOR"].default_value = values["IOR"]
    metal = group_node(tree, metal_group, (node.location.x - 200, node.location.y - 200))
    for name, socket in inputs.items():
        feed(tree, layered.inputs[name], socket)
        feed(tree, metal.inputs["Color" if name == "Base Color" else name], socket)
    mix = tree.nodes.new("ShaderNodeMixShader")
    feed(tree, mix.inputs[0], metallic)
    tree.links.new(shader_output(layered), mix.inputs[1])
    tree.links.new(shader_output(metal), mix.inputs[2])
    replace_node(tree, node, mix)
    return True


def mix_layered_twin(tree, node, item):
    parts = layering_parts(node)
    if parts is None:
        return False
    factor, diffuse, glossy = parts
    inputs = {"Base Color": diffuse.inputs["Color"], "Roughness": glossy.inputs["Roughness"],
              "Normal": glossy.inputs["Normal"]}
    values = {}
    if factor.bl_idname == "ShaderNodeFresnel":
        inputs["IOR"] = factor.inputs["IOR"]
    else:
        values["IOR"] = item["detail"]["ior"]
    return group_in_place(tree, node, item["twin"], inputs, values)


def add_scaled(tree, node, item):
    """An Add Shader whose sum creates energy, scaled by item["scale"] (1 over
    the brightness measured): a Mix Shader after it, with nothing on its other
    input, passes that fraction. No scale (a twin): left as it is."""
    scale = item.get("scale")
    if scale is None or not 0.0 < scale < 1.0:
        return False
    mix = tree.nodes.new("ShaderNodeMixShader")
    mix.inputs[0].default_value = 1.0 - scale
    mix.location = node.location.x + 200, node.location.y
    mix.parent = node.parent
    out = shader_output(node)
    for link in list(out.links):
        tree.links.new(mix.outputs["Shader"], link.to_socket)
    tree.links.new(out, mix.inputs[1])
    return True


def clamp_color(tree, node, item):
    sock = next((s for s in node.inputs if s.identifier == item["detail"]["input"]), None)
    if sock is None or sock.is_linked:
        return False
    value = list(sock.default_value)
    sock.default_value = [min(c, 1.0) for c in value[:3]] + value[3:]
    return True


def toon_sharp(tree, node, item):
    sock = node.inputs["Smooth"]
    for link in list(sock.links):
        tree.links.remove(link)
    sock.default_value = 0.0
    return True


REPLACEMENTS = {
    "glossy-single-scatter": twin_in_place,
    "anisotropic-multiscatter": twin_in_place,
    "metallic-single-scatter": to_multiscatter,
    "glass-single-scatter": twin_in_place,
    "refraction-single-scatter": twin_in_place,
    "principled-single-scatter": to_multiscatter,
    "principled-creates-energy": principled_layered_twin,
    "mix-fresnel-layering": mix_layered_twin,
    "add-reflecting": add_scaled,
    "color-above-one": clamp_color,
    "toon-smooth": toon_sharp,
}


def has_replacement(item):
    """Whether a twin replaces the finding's node (an Add Shader is only scaled by a fix)."""
    return item["twin"] is not None and item["rule"] in REPLACEMENTS \
        and (item["rule"] != "add-reflecting" or item.get("scale") is not None)


# --- applying along a path -----------------------------------------------------------

def tree_along(tree, path, copies):
    """The tree holding the node at `path` (material name first, node name last).
    With `copies` ({original tree name: copy}), each group on the way gets its
    own copy, once per tree; without, the real trees (edited in place), and
    None past a linked one."""
    for name in path[1:-1]:
        group_node = tree.nodes.get(name)
        if group_node is None or getattr(group_node, "node_tree", None) is None:
            return None
        sub = group_node.node_tree
        if copies is None and sub.library is not None:
            return None  # a linked group is read-only here: its library must be fixed
        if copies is not None and sub not in copies.values():
            if sub.name not in copies:
                copies[sub.name] = sub.copy()
            group_node.node_tree = copies[sub.name]
        tree = group_node.node_tree
    return tree


def apply_finding(tree, item, copies=None):
    """Apply one finding's replacement; False when it has none or its node is
    gone or already replaced (a shared group fixed through an earlier material)."""
    if not has_replacement(item):
        return False
    holder = tree_along(tree, item["node"], copies)
    node = holder.nodes.get(item["node"][-1]) if holder is not None else None
    if node is None or node.bl_idname != item["node_type"]:
        return False
    return REPLACEMENTS[item["rule"]](holder, node, item)


def make_twin(material, findings):
    """The material's twin with every replacement applied, and how many were;
    (None, 0) when nothing is replaced."""
    if not any(has_replacement(item) for item in findings):
        return None, 0
    twin = material.copy()
    twin.name = material.name + TWIN_SUFFIX
    tree = material_node_tree(twin)
    copies = {}
    replaced = sum(1 for item in findings if apply_finding(tree, item, copies))
    if replaced == 0:
        bpy.data.materials.remove(twin)
        for copy in copies.values():
            bpy.data.node_groups.remove(copy)
        return None, 0
    return twin, replaced


# --- the file's own groups, and what this run added ------------------------------------

def set_aside_groups(names):
    """Rename the file's groups called one of `names` out of the way before
    build_all, which would rebuild them in place (and change what the user's
    materials render). Returns [(tree, old name), ...] for restore_groups."""
    kept = []
    for tree in list(bpy.data.node_groups):
        if tree.library is None and tree.name in names:
            kept.append((tree, tree.name))
            tree.name = tree.name + SET_ASIDE_SUFFIX
    return kept


def restore_groups(kept):
    """Give set-aside groups their names back (Blender adds .001 where the name
    is now taken by a group this run added and uses)."""
    for tree, name in kept:
        tree.name = name


def real_users(id_block):
    return id_block.users - (1 if id_block.use_fake_user else 0)


def remove_unused_added(before):
    """Remove the node groups and images that were not in the file (`before`:
    set of (collection name, datablock pointer)) and that nothing uses;
    repeated, since removing a group frees the groups and images it used."""
    removed = True
    while removed:
        removed = False
        for collection in (bpy.data.node_groups, bpy.data.images):
            for block in list(collection):
                if block.as_pointer() not in before and real_users(block) == 0:
                    collection.remove(block)
                    removed = True


def datablock_pointers():
    return {block.as_pointer() for collection in (bpy.data.node_groups, bpy.data.images)
            for block in collection}
