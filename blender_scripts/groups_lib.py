# ---------------------------------------------------------------------------
# gloffuse groups library: builds the brightness-correction node groups.
#
# This file is pasted verbatim after a header that defines GLOFFUSE_PARAMS (a
# JSON document as a Python string), and before a "main" (generate_main.py or
# the furnace script). It defines functions only; nothing runs on import.
# Works in Blender 3.4 .. 5.0 (binary, Text Editor, or the `bpy` module).
#
# Public API used by the main scripts:
#   load_params(text) -> dict             parse and validate the parameter JSON
#   build_all(params) -> [(spec, [trees...]), ...]
#   build_correction_group(spec, params) -> correction tree
#   build_shader_group(spec, params, correction_tree) -> shader tree
#   blender_version_string() -> "4.5.15"
#   script_args(argv=None) -> the arguments meant for the script
#   ScriptArgumentParser, parse_script_args(parser) -> options (never exits)
#   run_main(main) -> runs main with the error handling described there
#   result_line(payload) -> "GLOFFUSE_RESULT {...}"
# ---------------------------------------------------------------------------
import argparse
import json
import math
import os
import sys
import traceback

import bpy

DISTRIBUTIONS = ("BECKMANN", "GGX", "ASHIKHMIN_SHIRLEY")
CURVE_VARIABLES = ("roughness", "alpha")

# Layout of the generated nodes (Blender node-editor units).
NODE_WIDTH = 180.0
COLUMN_STEP = 230.0   # NODE_WIDTH plus a 50-unit gap
ROW_STEP = 240.0      # taller than a Math node showing three inputs
FRAME_INSET = 250.0   # first column inside the frame, clear of the Group Input


# ---------------------------------------------------------------------------
# Compatibility shim: every difference between Blender versions lives here.
# ---------------------------------------------------------------------------

def blender_version_string():
    """Blender's version as "major.minor.patch" (no "LTS" suffix)."""
    return ".".join(str(part) for part in bpy.app.version)


def has_interface_api(tree):
    """Blender 4.0+ describes group sockets with tree.interface."""
    return hasattr(tree, "interface")


# Blender 3.x encodes a float socket's subtype in the socket type name.
_LEGACY_SUBTYPE_SUFFIX = {"FACTOR": "Factor"}


def new_socket(tree, name, in_out, socket_type, subtype=None):
    """Append a group socket. in_out is 'INPUT' or 'OUTPUT'; socket_type is a
    base type name such as 'NodeSocketFloat'. Returns the interface socket,
    on which default_value, min_value, max_value and hide_value live."""
    if has_interface_api(tree):
        sock = tree.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
        if subtype and hasattr(sock, "subtype"):
            sock.subtype = subtype
        return sock
    idname = socket_type + _LEGACY_SUBTYPE_SUFFIX.get(subtype, "")
    sockets = tree.inputs if in_out == "INPUT" else tree.outputs
    return sockets.new(idname, name)


def interface_sockets(tree, in_out):
    """The group's sockets of one direction, in order."""
    if has_interface_api(tree):
        return [item for item in tree.interface.items_tree
                if item.item_type == "SOCKET" and item.in_out == in_out]
    return list(tree.inputs if in_out == "INPUT" else tree.outputs)


def interface_has_panels(tree):
    if not has_interface_api(tree):
        return False
    return any(item.item_type != "SOCKET" for item in tree.interface.items_tree)


def socket_type_of(sock):
    """Base socket type name ('NodeSocketFloat', ...) of an interface socket."""
    if hasattr(sock, "socket_type"):
        return sock.socket_type
    idname = sock.bl_socket_idname  # 3.x: 'NodeSocketFloatFactor' and the like
    return "NodeSocketFloat" if idname.startswith("NodeSocketFloat") else idname


def clear_interface(tree):
    """Remove every group socket (and panel)."""
    if has_interface_api(tree):
        tree.interface.clear()
    else:
        tree.inputs.clear()
        tree.outputs.clear()


def set_tree_description(tree, text):
    """NodeTree.description exists from Blender 4.0 (shown as a tooltip)."""
    if hasattr(tree, "description"):
        tree.description = text


def mark_asset(tree, description, tags):
    """Mark the group as an asset (Blender 3.0+) so it shows in the Asset
    Browser, with a description and tags. Does nothing where unsupported."""
    if not hasattr(tree, "asset_mark"):
        return False
    if getattr(tree, "asset_data", None) is None:
        tree.asset_mark()
    data = getattr(tree, "asset_data", None)
    if data is None:
        return False
    if hasattr(data, "description"):
        data.description = description
    if hasattr(data, "author") and not data.author:
        data.author = "gloffuse"
    if hasattr(data, "tags"):
        present = {tag.name for tag in data.tags}
        for tag in tags:
            if tag not in present:
                data.tags.new(tag, skip_if_exists=True)
    return True


def glossy_node(nodes, distribution):
    """A Glossy BSDF with an explicit distribution. In 4.0+ the Glossy node is
    the former Anisotropic node (idname ShaderNodeBsdfAnisotropic) and a new
    one defaults to MULTI_GGX, so the distribution is always set."""
    node = nodes.new("ShaderNodeBsdfGlossy")
    allowed = [item.identifier for item in
               node.bl_rna.properties["distribution"].enum_items]
    if distribution not in allowed:
        raise ValueError("Blender %s's Glossy BSDF has no distribution %r (it has %s)"
                         % (blender_version_string(), distribution, ", ".join(allowed)))
    node.distribution = distribution
    return node


def find_socket(sockets, identifier):
    for sock in sockets:
        if sock.identifier == identifier:
            return sock
    raise KeyError("no socket with identifier %r" % identifier)


def multiply_color_node(nodes):
    """A colour multiply with factor 1: returns (node, a_in, b_in, out).
    ShaderNodeMix (3.4+) in RGBA/MULTIPLY mode, sockets found by identifier
    because several share the names A, B and Result; the legacy MixRGB node
    where ShaderNodeMix does not exist."""
    if hasattr(bpy.types, "ShaderNodeMix"):
        node = nodes.new("ShaderNodeMix")
        node.data_type = "RGBA"
        node.blend_type = "MULTIPLY"
        node.clamp_factor = True
        node.clamp_result = False
        fac = find_socket(node.inputs, "Factor_Float")
        a = find_socket(node.inputs, "A_Color")
        b = find_socket(node.inputs, "B_Color")
        out = find_socket(node.outputs, "Result_Color")
    else:
        node = nodes.new("ShaderNodeMixRGB")
        node.blend_type = "MULTIPLY"
        node.use_clamp = False
        fac, a, b = node.inputs[0], node.inputs[1], node.inputs[2]
        out = node.outputs[0]
    fac.default_value = 1.0
    return node, a, b, out


def set_parent(node, frame):
    """Put node in frame. The frame sits at the origin, so a child's location
    means the same whether Blender stores it relative to the frame (before 4.4)
    or absolute (4.4+)."""
    node.parent = frame


# ---------------------------------------------------------------------------
# Parameters
# ---------------------------------------------------------------------------

def _max_name_bytes():
    try:
        return bpy.types.ID.bl_rna.properties["name"].length_max - 1
    except (AttributeError, KeyError):
        return 63


def _finite_list(value, what):
    if not isinstance(value, list) or not value:
        raise ValueError("%s must be a non-empty list of numbers" % what)
    out = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, (int, float)) \
                or not math.isfinite(float(item)):
            raise ValueError("%s holds %r, which is not a finite number" % (what, item))
        out.append(float(item))
    return out


def validate_params(params):
    """Check the parameter document; raise ValueError saying what is wrong."""
    if not isinstance(params, dict):
        raise ValueError("the parameter document must be a JSON object")
    groups = params.get("groups")
    if not isinstance(groups, list) or not groups:
        raise ValueError("the parameter document needs a non-empty 'groups' list")
    limit = _max_name_bytes()
    seen = set()
    for index, spec in enumerate(groups):
        where = "groups[%d]" % index
        if not isinstance(spec, dict):
            raise ValueError("%s must be an object" % where)
        if spec.get("distribution") not in DISTRIBUTIONS:
            raise ValueError("%s.distribution is %r; expected one of %s"
                             % (where, spec.get("distribution"), ", ".join(DISTRIBUTIONS)))
        for key in ("correction_group", "shader_group"):
            name = spec.get(key)
            if not isinstance(name, str) or not name.strip():
                raise ValueError("%s.%s must be a non-empty string" % (where, key))
            if len(name.encode("utf-8")) > limit:
                raise ValueError("%s.%s %r is longer than Blender's %d-byte name limit"
                                 % (where, key, name, limit))
            if name in seen:
                raise ValueError("%s.%s %r is used twice" % (where, key, name))
            seen.add(name)
        view = spec.get("view")
        if view is not None:
            if not isinstance(view, dict):
                raise ValueError("%s.view must be an object" % where)
            for key in ("correction_group", "shader_group", "multiscatter_group", "image"):
                name = view.get(key)
                if not isinstance(name, str) or not name.strip():
                    raise ValueError("%s.view.%s must be a non-empty string" % (where, key))
                if len(name.encode("utf-8")) > limit:
                    raise ValueError("%s.view.%s %r is longer than Blender's %d-byte name limit"
                                     % (where, key, name, limit))
                if key != "image":
                    if name in seen:
                        raise ValueError("%s.view.%s %r is used twice" % (where, key, name))
                    seen.add(name)
            table = view.get("table")
            if not isinstance(table, dict) or not all(
                    isinstance(table.get(k), int) and table.get(k) >= 2 for k in ("width", "height")):
                raise ValueError("%s.view.table needs integer width and height of at least 2" % where)
        if not isinstance(spec.get("description", ""), str):
            raise ValueError("%s.description must be a string" % where)
        curve = spec.get("curve")
        if not isinstance(curve, dict):
            raise ValueError("%s.curve must be an object" % where)
        if curve.get("variable") not in CURVE_VARIABLES:
            raise ValueError("%s.curve.variable is %r; expected 'roughness' or 'alpha'"
                             % (where, curve.get("variable")))
        for key in ("numerator", "denominator"):
            coeffs = _finite_list(curve.get(key), "%s.curve.%s" % (where, key))
            if not any(coeffs):
                raise ValueError("%s.curve.%s is identically zero" % (where, key))
    return params


def load_params(text):
    """Parse the JSON parameter document and validate it."""
    return validate_params(json.loads(text))


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


def group_description(spec, params, kind):
    """Description for the tree and its asset: the spec's own text, then what
    the group computes and where its coefficients come from."""
    curve = spec["curve"]
    if kind == "correction":
        what = ("Brightness gain for Blender's %s Glossy BSDF: Gain = 100 / f(x), %s. "
                "Color output = input Color \u00d7 Gain."
                % (spec["distribution"], curve_text(curve)))
    else:
        what = ("Glossy BSDF (%s) whose colour is multiplied by the gain of '%s', so an "
                "evenly lit white surface keeps its brightness as roughness grows."
                % (spec["distribution"], spec["correction_group"]))
    source = "Coefficients: %s. Generated by gloffuse %s in Blender %s." % (
        params.get("coefficients_source", "unknown"),
        params.get("gloffuse_version", "?"),
        blender_version_string())
    parts = [spec.get("description", "").strip(), what, source]
    return "\n\n".join(part for part in parts if part)


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

def reuse_or_create_group(name):
    """The local ShaderNodeTree called `name`, emptied of nodes, or a new one.
    Reusing the datablock keeps every material that uses it working (no
    ".001" copy, same pointer)."""
    for tree in bpy.data.node_groups:
        if tree.name == name and tree.library is None:
            if tree.bl_idname != "ShaderNodeTree":
                raise ValueError("a node group called %r already exists but is a %s, "
                                 "not a shader node group; rename it and run again"
                                 % (name, tree.bl_idname))
            tree.nodes.clear()
            return tree
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    if tree.name != name:
        raise ValueError("Blender renamed the new node group %r to %r" % (name, tree.name))
    return tree


def _socket_signature(in_out, name, socket_type, subtype):
    """What must match for an existing socket to be kept. In 3.x the subtype
    is part of the socket type, so it is part of the signature there."""
    sig = (in_out, name, socket_type)
    if subtype is not None:
        sig += (subtype,)
    return sig


def _existing_signature(tree, in_out, sock):
    subtype = None
    if not has_interface_api(tree):
        for key, suffix in _LEGACY_SUBTYPE_SUFFIX.items():
            if sock.bl_socket_idname == "NodeSocketFloat" + suffix:
                subtype = key
    return _socket_signature(in_out, sock.name, socket_type_of(sock), subtype)


def ensure_interface(tree, sockets):
    """Give the tree exactly these sockets, in order.

    sockets: list of dicts with in_out, name, type, and optional subtype,
    default, min, max, hide_value, description. When the existing sockets
    already have the same directions, names and types, they are updated in
    place: their identifiers stay, so links from the group nodes in materials
    survive a re-run. Otherwise the interface is rebuilt."""
    legacy = not has_interface_api(tree)
    wanted = []
    have = []
    for in_out in ("INPUT", "OUTPUT"):
        for spec in sockets:
            if spec["in_out"] == in_out:
                subtype = spec.get("subtype") if legacy else None
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
        if spec.get("subtype") and hasattr(sock, "subtype"):
            sock.subtype = spec["subtype"]
        if "description" in spec and hasattr(sock, "description"):
            sock.description = spec["description"]
        if "min" in spec:
            sock.min_value = spec["min"]
        if "max" in spec:
            sock.max_value = spec["max"]
        if "default" in spec:
            sock.default_value = spec["default"]
        if hasattr(sock, "hide_value"):
            sock.hide_value = bool(spec.get("hide_value", False))


CORRECTION_SOCKETS = [
    {"in_out": "INPUT", "name": "Roughness", "type": "NodeSocketFloat", "subtype": "FACTOR",
     "default": 0.5, "min": 0.0, "max": 1.0,
     "description": "Roughness of the glossy BSDF (clamped to 0..1)"},
    {"in_out": "INPUT", "name": "Color", "type": "NodeSocketColor",
     "default": (1.0, 1.0, 1.0, 1.0),
     "description": "Colour to brighten"},
    {"in_out": "OUTPUT", "name": "Color", "type": "NodeSocketColor",
     "description": "Input Color multiplied by Gain"},
    {"in_out": "OUTPUT", "name": "Gain", "type": "NodeSocketFloat",
     "description": "Brightness gain 100 / f(x) for this roughness"},
]

SHADER_SOCKETS = [
    {"in_out": "INPUT", "name": "Color", "type": "NodeSocketColor",
     "default": (1.0, 1.0, 1.0, 1.0), "description": "Colour of the glossy reflection"},
    {"in_out": "INPUT", "name": "Roughness", "type": "NodeSocketFloat", "subtype": "FACTOR",
     "default": 0.5, "min": 0.0, "max": 1.0, "description": "Roughness (0..1)"},
    {"in_out": "INPUT", "name": "Normal", "type": "NodeSocketVector", "hide_value": True,
     "description": "Shading normal; unconnected means the surface's own normal"},
    {"in_out": "OUTPUT", "name": "BSDF", "type": "NodeSocketShader",
     "description": "Brightness-corrected glossy BSDF"},
]


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


def horner_chain(tree, coefficients, x_socket, column, y, prefix, frame):
    """Evaluate sum(c_k x^k) with one MULTIPLY_ADD node per power of x:
    acc = c_n; acc = acc * x + c_k for k = n-1 .. 0. Returns (output socket
    or None, constant value or None, number of columns used). A constant
    polynomial needs no node."""
    coeffs = trim_coefficients(coefficients)
    if len(coeffs) == 1:
        return None, coeffs[0], 0
    links = tree.links
    previous = None
    used = 0
    for k in range(len(coeffs) - 2, -1, -1):
        add = coeffs[k]
        sign = "-" if add < 0 else "+"
        if previous is None:
            label = "%s: %s \u00d7 x %s %s" % (prefix, fmt(coeffs[k + 1]), sign, fmt(abs(add)))
        else:
            label = "%s: \u00d7 x %s %s" % (prefix, sign, fmt(abs(add)))
        x = FRAME_INSET + COLUMN_STEP * (column + used)
        node = math_node(tree, "MULTIPLY_ADD", label, (x, y), frame, "%s x^%d" % (prefix, k))
        if previous is None:
            node.inputs[0].default_value = coeffs[k + 1]
        else:
            links.new(previous, node.inputs[0])
        links.new(x_socket, node.inputs[1])
        node.inputs[2].default_value = add
        previous = node.outputs[0]
        used += 1
    return previous, None, used


def build_correction_group(spec, params):
    """The group Roughness, Color -> Color, Gain with Gain = 100 den(x) / num(x)."""
    tree = reuse_or_create_group(spec["correction_group"])
    ensure_interface(tree, CORRECTION_SOCKETS)
    curve = spec["curve"]
    nodes, links = tree.nodes, tree.links

    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)

    frame = nodes.new("NodeFrame")
    frame.name = "Gain frame"
    frame.label = frame_label(curve)
    frame.shrink = True
    frame.location = (0.0, 0.0)

    column = 0
    clamp = nodes.new("ShaderNodeClamp")
    clamp.name = "Clamp roughness"
    clamp.label = "r = clamp(Roughness)"
    clamp.clamp_type = "MINMAX"
    clamp.inputs["Min"].default_value = 0.0
    clamp.inputs["Max"].default_value = 1.0
    clamp.width = NODE_WIDTH
    set_parent(clamp, frame)
    clamp.location = (FRAME_INSET, 0.0)
    links.new(group_in.outputs["Roughness"], clamp.inputs["Value"])
    x_socket = clamp.outputs[0]
    column += 1

    if curve["variable"] == "alpha":
        square = math_node(tree, "MULTIPLY", "x = alpha = r\u00b2",
                           (FRAME_INSET + COLUMN_STEP * column, 0.0), frame, "Square")
        links.new(x_socket, square.inputs[0])
        links.new(x_socket, square.inputs[1])
        x_socket = square.outputs[0]
        column += 1
    else:
        clamp.label = "x = clamp(Roughness)"

    num_out, num_const, num_cols = horner_chain(
        tree, curve["numerator"], x_socket, column, 0.0, "num", frame)
    den_out, den_const, den_cols = horner_chain(
        tree, curve["denominator"], x_socket, column, -ROW_STEP, "den", frame)
    column += max(num_cols, den_cols)

    def col_x():
        return FRAME_INSET + COLUMN_STEP * column

    # Gain = 100 * den / num.
    if den_out is None and num_out is None:
        gain = nodes.new("ShaderNodeValue")
        gain.name = "Gain"
        gain.label = "Gain (constant)"
        gain.outputs[0].default_value = 100.0 * den_const / num_const
        set_parent(gain, frame)
        gain.location = (col_x(), 0.0)
        gain_out = gain.outputs[0]
    else:
        if den_out is None:
            scaled = None
            top = 100.0 * den_const
        else:
            scaled = math_node(tree, "MULTIPLY", "100 \u00d7 den", (col_x(), -ROW_STEP),
                               frame, "Scale den")
            links.new(den_out, scaled.inputs[0])
            scaled.inputs[1].default_value = 100.0
            column += 1
        if num_out is None:
            label = "Gain = 100 den / %s" % fmt(num_const)
        elif scaled is None:
            label = "Gain = %s / num" % fmt(top)
        else:
            label = "Gain = 100 den / num"
        gain = math_node(tree, "DIVIDE", label, (col_x(), 0.0), frame, "Gain")
        if scaled is None:
            gain.inputs[0].default_value = top
        else:
            links.new(scaled.outputs[0], gain.inputs[0])
        if num_out is None:
            gain.inputs[1].default_value = num_const
        else:
            links.new(num_out, gain.inputs[1])
        gain_out = gain.outputs[0]
    column += 1

    mix, color_a, color_b, mix_out = multiply_color_node(nodes)
    mix.name = "Apply gain"
    mix.label = "Color \u00d7 Gain"
    mix.width = NODE_WIDTH
    mix.location = (col_x() + 50.0, 0.0)
    links.new(group_in.outputs["Color"], color_a)
    links.new(gain_out, color_b)

    group_out = nodes.new("NodeGroupOutput")
    group_out.location = (col_x() + 50.0 + COLUMN_STEP, 0.0)
    links.new(mix_out, group_out.inputs["Color"])
    links.new(gain_out, group_out.inputs["Gain"])

    description = group_description(spec, params, "correction")
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"]])
    return tree


def build_shader_group(spec, params, correction_tree):
    """The group Color, Roughness, Normal -> BSDF: a Glossy BSDF whose colour
    goes through the correction group."""
    description = group_description(spec, params, "shader")
    return build_glossy_group(spec["shader_group"], spec, correction_tree, description,
                              ["gloffuse", spec["distribution"]])


def build_glossy_group(name, spec, correction_tree, description, tags):
    """Color, Roughness, Normal -> BSDF: a Glossy BSDF of the spec's distribution
    whose colour goes through `correction_tree` (roughness-only or view)."""
    tree = reuse_or_create_group(name)
    ensure_interface(tree, SHADER_SOCKETS)
    nodes, links = tree.nodes, tree.links

    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)

    correction = nodes.new("ShaderNodeGroup")
    correction.node_tree = correction_tree
    correction.name = "Brightness correction"
    correction.label = short_label(correction_tree.name)
    correction.width = 260.0
    correction.location = (COLUMN_STEP + 20.0, 160.0)
    links.new(group_in.outputs["Roughness"], correction.inputs["Roughness"])
    links.new(group_in.outputs["Color"], correction.inputs["Color"])

    glossy = glossy_node(nodes, spec["distribution"])
    glossy.name = "Glossy BSDF"
    glossy.label = short_label("Glossy BSDF (%s)" % spec["distribution"])
    glossy.width = NODE_WIDTH
    glossy.location = (2 * COLUMN_STEP + 100.0, 0.0)
    links.new(correction.outputs["Color"], glossy.inputs["Color"])
    links.new(group_in.outputs["Roughness"], glossy.inputs["Roughness"])
    # An unconnected group Normal (hide_value, value (0,0,0)) reaches the BSDF
    # as "not linked": Cycles then uses the shading normal, as for a plain
    # Glossy node. Checked by rendering in 3.4, 4.5 and 5.0 (check_generated.py).
    links.new(group_in.outputs["Normal"], glossy.inputs["Normal"])

    group_out = nodes.new("NodeGroupOutput")
    group_out.location = (3 * COLUMN_STEP + 100.0, 0.0)
    links.new(glossy.outputs[0], group_out.inputs["BSDF"])

    set_tree_description(tree, description)
    mark_asset(tree, description, tags)
    return tree


# ---------------------------------------------------------------------------
# View-dependent and multiple-scattering groups (spec["view"])
#
# The directional albedo E(mu, r) travels as a table in the parameters and is
# packed into the .blend as a 32-bit float OpenEXR image. An Image Texture node
# samples it at (u, v) = pixel centres of (r, mu), with mu = N.I from the
# Geometry node, so Cycles' linear interpolation reproduces the table exactly
# at its grid points.
# ---------------------------------------------------------------------------

VIEW_CORRECTION_SOCKETS = CORRECTION_SOCKETS[:3] + [
    {"in_out": "OUTPUT", "name": "Gain", "type": "NodeSocketFloat",
     "description": "Brightness gain 1 / E(mu, r) for this roughness and view"},
]

MULTISCATTER_SOCKETS = SHADER_SOCKETS[:3] + [
    {"in_out": "OUTPUT", "name": "BSDF", "type": "NodeSocketShader",
     "description": "Glossy BSDF plus a diffuse lobe carrying the energy it loses"},
]


def albedo_image(view):
    """The packed float image holding E(mu, r): reused by name, resized if needed.
    Row i is mu = i / (height - 1) (row 0 at the bottom, Blender's order), column
    j is r = j / (width - 1); E is stored in RGB and alpha (channel packed)."""
    table = view["table"]
    width, height = int(table["width"]), int(table["height"])
    values = _finite_list(table["values"], "view.table.values")
    if len(values) != width * height:
        raise ValueError("view.table holds %d values, not %d x %d" % (len(values), width, height))
    name = view["image"]
    image = bpy.data.images.get(name)
    if image is not None and tuple(image.size) != (width, height):
        image.scale(width, height)
    if image is None:
        image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    image.alpha_mode = "CHANNEL_PACKED"
    pixels = []
    for value in values:
        pixels.extend((value, value, value, value))
    image.pixels.foreach_set(pixels)
    image.update()
    image.file_format = "OPEN_EXR"
    image.pack()
    return image


def albedo_lookup(tree, view, roughness_socket, x, frame):
    """Nodes that output E(mu, r) for the clamped roughness socket; x is the
    first column. Returns the float socket."""
    nodes, links = tree.nodes, tree.links
    table = view["table"]
    width, height = int(table["width"]), int(table["height"])

    def at(column, y=0.0):
        return (FRAME_INSET + COLUMN_STEP * (x + column), y)

    geometry = nodes.new("ShaderNodeNewGeometry")
    geometry.name = "Geometry"
    set_parent(geometry, frame)
    geometry.location = at(0, -ROW_STEP)
    dot = nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    dot.name = "mu"
    dot.label = "mu = N · I"
    set_parent(dot, frame)
    dot.location = at(1, -ROW_STEP)
    links.new(geometry.outputs["Normal"], dot.inputs[0])
    links.new(geometry.outputs["Incoming"], dot.inputs[1])
    # Pixel centres: u = r (W-1)/W + 1/(2W), clamped into the table.
    u = math_node(tree, "MULTIPLY_ADD", "u = r (W-1)/W + 1/2W", at(1), frame, "u")
    u.use_clamp = True
    links.new(roughness_socket, u.inputs[0])
    u.inputs[1].default_value = (width - 1.0) / width
    u.inputs[2].default_value = 0.5 / width
    v = math_node(tree, "MULTIPLY_ADD", "v = mu (H-1)/H + 1/2H", at(2, -ROW_STEP), frame, "v")
    v.use_clamp = True
    links.new(dot.outputs["Value"], v.inputs[0])
    v.inputs[1].default_value = (height - 1.0) / height
    v.inputs[2].default_value = 0.5 / height
    uv = nodes.new("ShaderNodeCombineXYZ")
    uv.name = "uv"
    set_parent(uv, frame)
    uv.location = at(3)
    links.new(u.outputs[0], uv.inputs["X"])
    links.new(v.outputs[0], uv.inputs["Y"])
    texture = nodes.new("ShaderNodeTexImage")
    texture.name = "E(mu, r)"
    texture.label = short_label("E(mu, r) table %d x %d" % (width, height))
    texture.image = albedo_image(view)
    texture.interpolation = "Linear"
    texture.extension = "EXTEND"
    texture.width = 240.0
    set_parent(texture, frame)
    texture.location = at(4)
    links.new(uv.outputs[0], texture.inputs["Vector"])
    return texture.outputs["Alpha"], x + 5


def clamped_roughness(tree, group_in, frame):
    clamp = tree.nodes.new("ShaderNodeClamp")
    clamp.name = "Clamp roughness"
    clamp.label = "r = clamp(Roughness)"
    clamp.inputs["Min"].default_value = 0.0
    clamp.inputs["Max"].default_value = 1.0
    clamp.width = NODE_WIDTH
    set_parent(clamp, frame)
    clamp.location = (FRAME_INSET, 0.0)
    tree.links.new(group_in.outputs["Roughness"], clamp.inputs["Value"])
    return clamp.outputs[0]


def view_frame(tree, label):
    frame = tree.nodes.new("NodeFrame")
    frame.name = "Albedo frame"
    frame.label = short_label(label)
    frame.shrink = True
    frame.location = (0.0, 0.0)
    return frame


def view_description(spec, params, what):
    source = "Coefficients: %s. Generated by gloffuse %s in Blender %s." % (
        params.get("coefficients_source", "unknown"),
        params.get("gloffuse_version", "?"),
        blender_version_string())
    return "\n\n".join(p for p in [spec.get("description", "").strip(), what, source] if p)


def build_view_correction_group(spec, params):
    """Roughness, Color -> Color, Gain with Gain = 1 / E(mu, r)."""
    view = spec["view"]
    tree = reuse_or_create_group(view["correction_group"])
    ensure_interface(tree, VIEW_CORRECTION_SOCKETS)
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    frame = view_frame(tree, "Gain = 1 / E(mu, r), mu = N · I")
    r = clamped_roughness(tree, group_in, frame)
    albedo, column = albedo_lookup(tree, view, r, 1, frame)
    gain = math_node(tree, "DIVIDE", "Gain = 1 / E", (FRAME_INSET + COLUMN_STEP * column + 100.0, 0.0),
                     frame, "Gain")
    gain.inputs[0].default_value = 1.0
    links.new(albedo, gain.inputs[1])
    mix, color_a, color_b, mix_out = multiply_color_node(nodes)
    mix.name = "Apply gain"
    mix.label = "Color × Gain"
    mix.width = NODE_WIDTH
    x_end = FRAME_INSET + COLUMN_STEP * (column + 1) + 150.0
    mix.location = (x_end, 0.0)
    links.new(group_in.outputs["Color"], color_a)
    links.new(gain.outputs[0], color_b)
    group_out = nodes.new("NodeGroupOutput")
    group_out.location = (x_end + COLUMN_STEP, 0.0)
    links.new(mix_out, group_out.inputs["Color"])
    links.new(gain.outputs[0], group_out.inputs["Gain"])
    description = view_description(spec, params, (
        "View-dependent brightness gain for Blender's %s Glossy BSDF: Gain = 1 / E(mu, r), "
        "with mu = N · I from the Geometry node and E read from the packed table '%s', "
        "so every pixel of an evenly lit white surface is 100 %%." % (spec["distribution"], view["image"])))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "view"])
    return tree


def build_view_shader_group(spec, params, correction_tree):
    """Color, Roughness, Normal -> BSDF: Glossy with colour x 1 / E(mu, r)."""
    description = view_description(spec, params, (
        "Glossy BSDF (%s) whose colour is multiplied by the view-dependent gain of '%s'."
        % (spec["distribution"], correction_tree.name)))
    return build_glossy_group(spec["view"]["shader_group"], spec, correction_tree, description,
                              ["gloffuse", spec["distribution"], "view"])


def build_multiscatter_group(spec, params):
    """Color, Roughness, Normal -> BSDF: Glossy(Color) + Diffuse(Color x (1 - E(mu, r))):
    the energy single scattering loses comes back as a diffuse-like lobe."""
    view = spec["view"]
    tree = reuse_or_create_group(view["multiscatter_group"])
    ensure_interface(tree, MULTISCATTER_SOCKETS)
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    frame = view_frame(tree, "Lost energy 1 - E(mu, r), mu = N · I")
    r = clamped_roughness(tree, group_in, frame)
    albedo, column = albedo_lookup(tree, view, r, 1, frame)
    x = FRAME_INSET + COLUMN_STEP * column + 100.0
    lost = math_node(tree, "SUBTRACT", "1 - E", (x, 0.0), frame, "Lost")
    lost.inputs[0].default_value = 1.0
    links.new(albedo, lost.inputs[1])
    mix, color_a, color_b, mix_out = multiply_color_node(nodes)
    mix.name = "Diffuse colour"
    mix.label = "Color × (1 - E)"
    mix.width = NODE_WIDTH
    mix.location = (x + COLUMN_STEP, -ROW_STEP)
    links.new(group_in.outputs["Color"], color_a)
    links.new(lost.outputs[0], color_b)
    glossy = glossy_node(nodes, spec["distribution"])
    glossy.name = "Glossy BSDF"
    glossy.label = short_label("Glossy BSDF (%s)" % spec["distribution"])
    glossy.width = NODE_WIDTH
    glossy.location = (x + 2 * COLUMN_STEP, 200.0)
    links.new(group_in.outputs["Color"], glossy.inputs["Color"])
    links.new(group_in.outputs["Roughness"], glossy.inputs["Roughness"])
    links.new(group_in.outputs["Normal"], glossy.inputs["Normal"])
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.name = "Diffuse BSDF"
    diffuse.width = NODE_WIDTH
    diffuse.location = (x + 2 * COLUMN_STEP, -ROW_STEP)
    links.new(mix_out, diffuse.inputs["Color"])
    links.new(group_in.outputs["Normal"], diffuse.inputs["Normal"])
    add = nodes.new("ShaderNodeAddShader")
    add.name = "Add"
    add.location = (x + 3 * COLUMN_STEP, 0.0)
    links.new(glossy.outputs[0], add.inputs[0])
    links.new(diffuse.outputs[0], add.inputs[1])
    group_out = nodes.new("NodeGroupOutput")
    group_out.location = (x + 4 * COLUMN_STEP, 0.0)
    links.new(add.outputs[0], group_out.inputs["BSDF"])
    description = view_description(spec, params, (
        "Glossy BSDF (%s) plus a diffuse lobe of colour Color × (1 - E(mu, r)): the "
        "energy single scattering loses comes back, so an evenly lit white surface is 100 %% "
        "at every pixel without brightening the highlight." % spec["distribution"]))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "multiscatter"])
    return tree


def build_all(params):
    """Build (or rebuild in place) every group in params["groups"]: for each
    spec the roughness-only pair, and with spec["view"] also the view pair and
    the multiscatter group. Returns [(spec, [trees...]), ...] in document order."""
    validate_params(params)
    built = []
    for spec in params["groups"]:
        correction = build_correction_group(spec, params)
        trees = [correction, build_shader_group(spec, params, correction)]
        if spec.get("view"):
            view_correction = build_view_correction_group(spec, params)
            trees.append(view_correction)
            trees.append(build_view_shader_group(spec, params, view_correction))
            trees.append(build_multiscatter_group(spec, params))
        built.append((spec, trees))
    return built


# ---------------------------------------------------------------------------
# Helpers for the main scripts
# ---------------------------------------------------------------------------

def running_in_blender_binary():
    """True inside the blender executable (its Text Editor or --python),
    False when Blender is imported as the `bpy` module."""
    return bool(bpy.app.binary_path)


def script_args(argv=None):
    """The arguments meant for the script: those after "--" if present;
    otherwise none inside the blender binary (Text Editor, or --python
    without "--"), and argv[1:] under a plain Python with the bpy module."""
    argv = list(sys.argv if argv is None else argv)
    if "--" in argv:
        return argv[argv.index("--") + 1:]
    if running_in_blender_binary():
        return []
    return argv[1:]


class ArgumentError(ValueError):
    """Bad command-line arguments for a gloffuse script."""


class ScriptArgumentParser(argparse.ArgumentParser):
    """argparse that raises ArgumentError instead of exiting, so a mistake
    never quits an interactive Blender."""

    def error(self, message):
        raise ArgumentError("%s: %s\n%s" % (self.prog, message, self.format_usage().strip()))


def parse_script_args(parser, argv=None):
    """Parse the script's arguments. Headless: strictly. Interactive (the Text
    Editor of a Blender that may have been started with other arguments after
    "--"): unknown arguments are reported and ignored."""
    args = script_args(argv)
    if bpy.app.background:
        return parser.parse_args(args)
    options, ignored = parser.parse_known_args(args)
    if ignored:
        sys.stderr.write("%s: ignoring arguments %s\n" % (parser.prog, " ".join(ignored)))
    return options


def open_blend(path):
    path = os.path.abspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError("no .blend file at %s" % path)
    bpy.ops.wm.open_mainfile(filepath=path)
    return path


def save_blend(path):
    """Save the open file as `path` without a .blend1 backup (the caller
    handles backups and atomic renames)."""
    path = os.path.abspath(path)
    directory = os.path.dirname(path)
    if directory and not os.path.isdir(directory):
        raise FileNotFoundError("the folder %s does not exist" % directory)
    filepaths = bpy.context.preferences.filepaths
    old_versions = filepaths.save_version
    filepaths.save_version = 0
    try:
        result = bpy.ops.wm.save_as_mainfile(filepath=path, check_existing=False,
                                             copy=False, compress=False)
    finally:
        filepaths.save_version = old_versions
    if "FINISHED" not in result or not os.path.isfile(path):
        raise RuntimeError("Blender could not save %s" % path)
    return path


def result_line(payload):
    """The one machine-readable line a main prints on stdout."""
    return "GLOFFUSE_RESULT " + json.dumps(payload, sort_keys=True)


def run_main(main):
    """Run main(); on error print the traceback and, headless, exit 1 (2 for
    bad arguments), because blender -b --python ignores exceptions unless
    --python-exit-code is given. Interactive (Text Editor) the exception is
    re-raised so Blender shows it and keeps running."""
    try:
        main()
    except ArgumentError as error:
        sys.stderr.write("%s\n" % error)
        sys.stderr.flush()
        if bpy.app.background:
            sys.exit(2)
        raise
    except Exception:
        traceback.print_exc()
        sys.stderr.flush()
        if bpy.app.background:
            sys.stdout.flush()
            sys.exit(1)
        raise

# ------------------------- end of the groups library -----------------------
