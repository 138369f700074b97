# ---------------------------------------------------------------------------
# gloffuse nodes.py: node-building helpers shared by the roughness-only and
# the view-dependent groups: layout, the curve as text and as numbers,
# reusing a group in place, its sockets, Math nodes, the clamped roughness,
# frames and descriptions.
#
# A module of the gloffuse_blender package. Functions and constants only;
# every version difference it meets goes through compat.py.
# ---------------------------------------------------------------------------
import hashlib
import json
import re

import bpy

from .compat import (
    blender_version_string,
    clear_interface,
    existing_signature_subtype,
    inputs_added_as_before,
    interface_has_panels,
    interface_sockets,
    multiply_color_node,
    new_socket,
    set_parent,
    set_socket_description,
    set_socket_hide_value,
    set_socket_subtype,
    signature_subtype,
    socket_type_of,
)

# Layout of the generated nodes (Blender node-editor units).
NODE_WIDTH = 180.0
COLUMN_STEP = 230.0   # NODE_WIDTH plus a 50-unit gap
ROW_STEP = 240.0      # taller than a Math node showing three inputs
FRAME_INSET = 250.0   # first column inside the frame, clear of the Group Input


# ---------------------------------------------------------------------------
# The curve as text and as numbers
# ---------------------------------------------------------------------------

def trim_coefficients(coefficients):
    """Ascending coefficients without trailing zeros (at least one kept)."""
    coeffs = [float(c) for c in coefficients]
    while len(coeffs) > 1 and coeffs[-1] == 0.0:
        coeffs.pop()
    return coeffs


def fmt(value):
    """A short, exact-looking number for labels: 38.0, -79.0, 0.123457."""
    text = repr(float(value))
    if len(text) > 9:
        text = "%.6g" % value
    return text


def polynomial_text(coefficients, var="x"):
    """'38.0 x³ - 79.0 x² + 100.0' (highest power first, zero terms left out)."""
    powers = {1: "", 2: "\u00b2", 3: "\u00b3"}
    terms = []
    for power in range(len(coefficients) - 1, -1, -1):
        c = coefficients[power]
        if c == 0.0 and len(coefficients) > 1:
            continue
        if power == 0:
            body = fmt(abs(c))
        else:
            body = "%s %s%s" % (fmt(abs(c)), var, powers.get(power, "^%d" % power))
        sign = "-" if c < 0 else "+"
        terms.append((sign, body))
    if not terms:
        return "0"
    first_sign, first_body = terms[0]
    text = ("-" if first_sign == "-" else "") + first_body
    for sign, body in terms[1:]:
        text += " %s %s" % (sign, body)
    return text


def curve_text(curve):
    """The curve f(x) in percent, as one line."""
    num = polynomial_text(trim_coefficients(curve["numerator"]))
    den = trim_coefficients(curve["denominator"])
    var = "x = roughness" if curve["variable"] == "roughness" else "x = roughness\u00b2"
    if len(den) == 1 and den[0] == 1.0:
        return "f(x) = %s  (%s)" % (num, var)
    return "f(x) = (%s) / (%s)  (%s)" % (num, polynomial_text(den), var)


def short_label(text, limit=63):
    """Blender keeps at most 63 bytes of a label: cut on a character boundary."""
    data = text.encode("utf-8")
    if len(data) <= limit:
        return text
    return data[:limit].decode("utf-8", "ignore")


def frame_label(curve):
    """'Gain = 100 / f(x), f(x) = 38.0 x³ - 79.0 x² + 100.0' when it fits in a
    label, else 'Gain = 100 / f(x)'."""
    num = trim_coefficients(curve["numerator"])
    den = trim_coefficients(curve["denominator"])
    if len(den) == 1:
        body = polynomial_text([c / den[0] for c in num])
    else:
        body = "(%s) / (%s)" % (polynomial_text(num), polynomial_text(den))
    text = "Gain = 100 / f(x),  f(x) = " + body
    return text if len(text.encode("utf-8")) <= 63 else "Gain = 100 / f(x)"


def gain_at(curve, roughness):
    """The gain 100 * den(x) / num(x) in plain Python (for tests and checks)."""
    x = min(max(float(roughness), 0.0), 1.0)
    if curve["variable"] == "alpha":
        x = x * x

    def horner(coeffs):
        acc = 0.0
        for c in reversed([float(v) for v in coeffs]):
            acc = acc * x + c
        return acc
    return 100.0 * horner(curve["denominator"]) / horner(curve["numerator"])


# ---------------------------------------------------------------------------
# Building the groups
# ---------------------------------------------------------------------------

# The custom property that marks a node group (and a library's scene) as made
# by gloffuse; its value is the gloffuse version. Only tagged groups are ever
# rebuilt: a group of the same name without it is the user's own.
GLOFFUSE_TAG = "gloffuse"


# The custom property holding a fingerprint of what gloffuse built in a group
# (content_fingerprint), written beside the tag: the audit trusts a group only
# while its tree is still exactly that.
GLOFFUSE_CONTENT = "gloffuse_content"


def is_tagged(id_block):
    return GLOFFUSE_TAG in id_block.keys()


def _rna_value(value):
    """A node setting or socket value as JSON: floats to 6 significant digits
    (what a save and a reload keep), vectors as lists, enum flags sorted."""
    if isinstance(value, float):
        return float("%.6g" % value)
    if isinstance(value, (bool, int, str)) or value is None:
        return value
    if isinstance(value, (set, frozenset)):
        return sorted(value)
    try:
        return [_rna_value(v) for v in value]
    except TypeError:
        return repr(value)


# Blender's ".001" on a datablock appended beside one of the same name: a group
# appended from the library after another one brings its own copy of their table.
DUPLICATE_SUFFIX = re.compile(r"\.\d{3,}$")


def _node_content(node, stack):
    """What a node renders with: its type, mute, its own settings (every
    writable property a plain node lacks), its unlinked inputs' values (but
    those a newer Blender adds at a value that changes nothing), and a nested
    group's content or an image's name (without a duplicate's suffix)."""
    base = {prop.identifier for prop in bpy.types.Node.bl_rna.properties}
    settings = {prop.identifier: _rna_value(getattr(node, prop.identifier))
                for prop in node.bl_rna.properties
                if prop.identifier not in base and not prop.is_readonly
                and prop.type in ("BOOLEAN", "INT", "FLOAT", "STRING", "ENUM")}
    added = inputs_added_as_before(node)
    inputs = [[sock.identifier, _rna_value(getattr(sock, "default_value", None))]
              for sock in node.inputs if not sock.is_linked and sock.identifier not in added]
    tree = getattr(node, "node_tree", None)
    image = getattr(node, "image", None)
    return [node.name, node.bl_idname, bool(node.mute), settings, inputs,
            None if tree is None else _tree_content(tree, stack),
            None if image is None else DUPLICATE_SUFFIX.sub("", image.name)]


def _tree_content(tree, stack=()):
    if tree.name in stack:  # a group inside itself: Blender refuses it, never loop
        return ["cycle", tree.name]
    stack = stack + (tree.name,)
    nodes = [_node_content(node, stack)
             for node in sorted(tree.nodes, key=lambda n: n.name) if node.bl_idname != "NodeFrame"]
    links = sorted([link.from_node.name, link.from_socket.identifier, link.to_node.name,
                    link.to_socket.identifier, bool(link.is_muted)] for link in tree.links)
    return [nodes, links]


def content_fingerprint(tree):
    """A hash of everything in `tree` that changes what it renders (nodes,
    their settings and unconnected values, links, nested groups): any edit
    after gloffuse built it changes it. Frames and layout are left out."""
    text = json.dumps(_tree_content(tree), sort_keys=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def is_gloffuse_group(tree):
    """A group exactly as gloffuse built it: tagged, and its content what the
    fingerprint written at build time says (a copy edited afterwards, or a
    user's group given the tag, is not)."""
    return is_tagged(tree) and tree.get(GLOFFUSE_CONTENT) == content_fingerprint(tree)


def set_aside_untagged(names):
    """Rename every local node group called one of `names` that carries no
    gloffuse tag (the user's own, or one made before tagging) to a free name,
    "NAME (yours)" (Blender adds .001 etc. if that is taken). Renaming keeps
    the datablock, so every material using it still does. Returns
    [[old name, new name], ...]."""
    renamed = []
    for tree in list(bpy.data.node_groups):
        if tree.library is not None or tree.name not in names or is_tagged(tree):
            continue
        old = tree.name
        tree.name = old + " (yours)"
        if tree.name in names or tree.name == old:
            raise ValueError("could not rename your node group %r out of the way; rename "
                             "it and run again" % old)
        renamed.append([old, tree.name])
    return renamed


def reuse_or_create_group(name):
    """The local ShaderNodeTree called `name`, emptied of nodes, or a new one.
    Reusing the datablock keeps every material that uses it working (no
    ".001" copy, same pointer). Untagged groups must have been set aside
    first (set_aside_untagged): one left here is refused, never emptied."""
    for tree in bpy.data.node_groups:
        if tree.name == name and tree.library is None:
            if not is_tagged(tree):
                raise ValueError("the node group %r was not made by gloffuse and was not "
                                 "set aside" % name)
            if tree.bl_idname != "ShaderNodeTree":
                raise ValueError("a node group called %r already exists but is a %s, "
                                 "not a shader node group; rename it and run again"
                                 % (name, tree.bl_idname))
            tree.nodes.clear()
            return tree
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    if tree.name != name:
        raise ValueError("Blender renamed the new node group %r to %r" % (name, tree.name))
    # Tagged at once (build_all writes the version), so a rebuild in this run reuses it.
    tree[GLOFFUSE_TAG] = ""
    return tree


def _socket_signature(in_out, name, socket_type, subtype):
    """What must match for an existing socket to be kept: direction, name,
    type, and the subtype where it is part of the type (compat.py's
    signature_subtype: 3.x only)."""
    sig = (in_out, name, socket_type)
    if subtype is not None:
        sig += (subtype,)
    return sig


def _existing_signature(tree, in_out, sock):
    return _socket_signature(in_out, sock.name, socket_type_of(sock),
                             existing_signature_subtype(tree, sock))


def ensure_interface(tree, sockets):
    """Give the tree exactly these sockets, in order.

    sockets: list of dicts with in_out, name, type, and optional subtype,
    default, min, max, hide_value, description. When the existing sockets
    already have the same directions, names and types, they are updated in
    place: their identifiers stay, so links from the group nodes in materials
    survive a re-run. Otherwise the interface is rebuilt."""
    wanted = []
    have = []
    for in_out in ("INPUT", "OUTPUT"):
        for spec in sockets:
            if spec["in_out"] == in_out:
                subtype = signature_subtype(tree, spec.get("subtype"))
                wanted.append(_socket_signature(in_out, spec["name"], spec["type"], subtype))
        for sock in interface_sockets(tree, in_out):
            have.append(_existing_signature(tree, in_out, sock))
    if wanted != have or interface_has_panels(tree):
        clear_interface(tree)
        for spec in sockets:
            new_socket(tree, spec["name"], spec["in_out"], spec["type"], spec.get("subtype"))
    for spec in sockets:
        sock = [s for s in interface_sockets(tree, spec["in_out"])
                if s.name == spec["name"]][0]
        set_socket_subtype(sock, spec.get("subtype"))
        if "description" in spec:
            set_socket_description(sock, spec["description"])
        if "min" in spec:
            sock.min_value = spec["min"]
        if "max" in spec:
            sock.max_value = spec["max"]
        if "default" in spec:
            sock.default_value = spec["default"]
        set_socket_hide_value(sock, bool(spec.get("hide_value", False)))


def math_node(tree, operation, label, location, parent=None, name=None):
    node = tree.nodes.new("ShaderNodeMath")
    node.operation = operation
    node.use_clamp = False
    node.label = short_label(label)
    if name:
        node.name = name
    node.width = NODE_WIDTH
    if parent is not None:
        set_parent(node, parent)
    node.location = location
    return node


def clamped_roughness(tree, group_in, frame, label="r = clamp(Roughness)"):
    """A Clamp node clamp(Roughness, 0, 1) in the frame's first column, fed by
    the Group Input's Roughness. Returns its output socket."""
    clamp = tree.nodes.new("ShaderNodeClamp")
    clamp.name = "Clamp roughness"
    clamp.label = label
    clamp.clamp_type = "MINMAX"
    clamp.inputs["Min"].default_value = 0.0
    clamp.inputs["Max"].default_value = 1.0
    clamp.width = NODE_WIDTH
    set_parent(clamp, frame)
    clamp.location = (FRAME_INSET, 0.0)
    tree.links.new(group_in.outputs["Roughness"], clamp.inputs["Value"])
    return clamp.outputs[0]


def apply_gain(tree, color, gain, location):
    """A colour multiply "Apply gain": `color` x `gain`, at `location`.
    Returns its output socket."""
    mix, color_a, color_b, color_out = multiply_color_node(tree.nodes)
    mix.name = "Apply gain"
    mix.label = "Color \u00d7 Gain"
    mix.width = NODE_WIDTH
    mix.location = location
    tree.links.new(color, color_a)
    tree.links.new(gain, color_b)
    return color_out


def gained_bsdf(tree, group_in, gain, bsdf, x):
    """The end of a shader group that divides Blender's own BSDF's colour by
    its albedo: Color x Gain at x, into `bsdf`'s Color one column on, `bsdf`
    into the group's BSDF output one more on."""
    colored_bsdf(tree, apply_gain(tree, group_in.outputs["Color"], gain, (x, 0.0)), bsdf, x)


def colored_bsdf(tree, color, bsdf, x):
    """The end of a shader group: `color` into `bsdf`'s Color, `bsdf` one
    column on from x, into the group's BSDF output one more on."""
    bsdf.width = NODE_WIDTH
    bsdf.location = (x + COLUMN_STEP, 0.0)
    tree.links.new(color, bsdf.inputs["Color"])
    group_out = tree.nodes.new("NodeGroupOutput")
    group_out.location = (x + 2 * COLUMN_STEP, 0.0)
    tree.links.new(bsdf.outputs[0], group_out.inputs["BSDF"])


def new_frame(tree, name, label):
    """The shrinking frame, at the origin (see compat.py's set_parent), that
    holds a group's arithmetic."""
    frame = tree.nodes.new("NodeFrame")
    frame.name = name
    frame.label = short_label(label)
    frame.shrink = True
    frame.location = (0.0, 0.0)
    return frame


def description_text(spec, params, what):
    """Description for a tree and its asset: the spec's own text, then `what`
    (what the group computes), then where its coefficients come from."""
    source = "Coefficients: %s. Generated by gloffuse %s in Blender %s." % (
        spec.get("coefficients_source", "unknown"),
        params.get("gloffuse_version", "?"),
        blender_version_string())
    parts = [spec.get("description", "").strip(), what, source]
    return "\n\n".join(part for part in parts if part)


class Chain:
    """Builds arithmetic in one tree as a column-by-column chain of Math and
    Vector Math nodes inside `frame`, starting at column `column`. Operands are
    sockets or constants (numbers, or 3-tuples for vectors); each call returns
    the new node's output socket. `column` afterwards is the next free one."""

    ROWS = 4

    def __init__(self, tree, frame, column=0, y=0.0):
        self.tree, self.frame = tree, frame
        self.column, self.y = column, y
        self._row = 0

    def _place(self, node, label, name):
        node.label = short_label(label)
        node.name = name or label
        node.width = NODE_WIDTH
        set_parent(node, self.frame)
        node.location = (FRAME_INSET + COLUMN_STEP * self.column, self.y - ROW_STEP * self._row)
        self._row += 1
        if self._row == self.ROWS:
            self._row = 0
            self.column += 1

    def skip(self, columns):
        """Leave `columns` columns to other nodes; go on at the top of the next."""
        self.column += columns + (1 if self._row else 0)
        self._row = 0

    def _feed(self, socket, value):
        if isinstance(value, bpy.types.NodeSocket):
            self.tree.links.new(value, socket)
        else:
            socket.default_value = value

    def math(self, operation, label, *operands, name=None):
        """A Math node (float operands)."""
        node = self.tree.nodes.new("ShaderNodeMath")
        node.operation = operation
        node.use_clamp = False
        for socket, value in zip(node.inputs, operands):
            self._feed(socket, value)
        self._place(node, label, name)
        return node.outputs[0]

    def vector(self, operation, label, *operands, name=None):
        """A Vector Math node; SCALE takes (vector, float). Returns the Value
        output for DOT_PRODUCT and LENGTH, else the Vector output."""
        node = self.tree.nodes.new("ShaderNodeVectorMath")
        node.operation = operation
        if operation == "SCALE":
            self._feed(node.inputs[0], operands[0])
            self._feed(node.inputs["Scale"], operands[1])
        else:
            for socket, value in zip(node.inputs, operands):
                self._feed(socket, value)
        self._place(node, label, name)
        if operation in ("DOT_PRODUCT", "LENGTH"):
            return node.outputs["Value"]
        return node.outputs["Vector"]

    def select(self, label, flag, when_zero, when_one):
        """when_zero + flag (when_one - when_zero) for vectors; flag is 0 or 1."""
        difference = self.vector("SUBTRACT", label + ": difference", when_one, when_zero)
        step = self.vector("SCALE", label + ": scaled", difference, flag)
        return self.vector("ADD", label, when_zero, step)

    def mix_value(self, label, t, at_zero, at_one):
        """at_zero + t (at_one - at_zero) for floats: a 0/1 flag selects, a
        fraction interpolates linearly."""
        difference = self.math("SUBTRACT", label + ": difference", at_one, at_zero)
        return self.math("MULTIPLY_ADD", label, difference, t, at_zero)

    def clamp(self, label, value, low, high):
        """A Clamp node: value clamped to [low, high]."""
        node = self.tree.nodes.new("ShaderNodeClamp")
        node.clamp_type = "MINMAX"
        for socket, operand in zip(node.inputs, (value, low, high)):
            self._feed(socket, operand)
        self._place(node, label, None)
        return node.outputs[0]


def asset_fields(params, kind):
    """The asset fields of a group of `kind` ("shader" for the groups with a
    BSDF output, "helper" for the others): its catalog (so that Blender 4.0+
    lists shader groups in Add > Shader, helpers in a sub-menu) and the
    author, licence and copyright of the parameter document."""
    catalog = (params.get("catalogs") or {}).get(kind) or {}
    return {
        "catalog_id": catalog.get("uuid"),
        "author": params.get("asset_author"),
        "license": params.get("asset_license"),
        "copyright": params.get("asset_copyright"),
    }
