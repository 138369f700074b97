# ---------------------------------------------------------------------------
# gloffuse roughness_groups.py: the roughness-only groups. The correction
# group (Roughness, Color -> Color, Gain with Gain = 100 / f(x), f the fitted
# curve) and the shader group (a Glossy BSDF whose colour goes through it).
#
# A module of the gloffuse_blender package. Functions and constants only.
#
#   build_correction_group(spec, params) -> correction tree
#   build_shader_group(spec, params, correction_tree) -> shader tree
# ---------------------------------------------------------------------------
from .compat import glossy_node, mark_asset, set_parent, set_tree_description
from .nodes import (
    COLUMN_STEP,
    FRAME_INSET,
    NODE_WIDTH,
    ROW_STEP,
    Chain,
    apply_gain,
    asset_fields,
    clamped_roughness,
    curve_text,
    description_text,
    ensure_interface,
    fmt,
    frame_label,
    math_node,
    new_frame,
    reuse_or_create_group,
    short_label,
    trim_coefficients,
)

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


def group_description(spec, params, kind):
    """Description for the tree and its asset: the spec's own text, then what
    the group computes and where its coefficients come from."""
    curve = spec["curve"]
    if kind == "correction":
        what = ("Brightness gain for Blender's %s Glossy BSDF: Gain = 100 / f(x), %s. %s"
                % (spec["distribution"], curve_text(curve),
                   "Color output = C / (1 - C (1 - 1/Gain)): the energy multiple bounces "
                   "add is tinted by the colour (physical colour model)."
                   if params.get("color_model") == "physical" else
                   "Color output = input Color \u00d7 Gain."))
    else:
        what = ("Glossy BSDF (%s) whose colour is multiplied by the gain of '%s', so an "
                "evenly lit white surface keeps its brightness as roughness grows."
                % (spec["distribution"], spec["correction_group"]))
    return description_text(spec, params, what)


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


def gain_nodes(tree, frame, num, den, column):
    """Gain = 100 den / num from the Horner chains' (output, constant) pairs, in the
    frame from `column` on; a chain that folded to a constant becomes a default
    value. Returns the gain socket and the column after it."""
    (num_out, num_const), (den_out, den_const) = num, den
    nodes, links = tree.nodes, tree.links

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
    return gain_out, column


def build_correction_group(spec, params):
    """The group Roughness, Color -> Color, Gain with Gain = 100 den(x) / num(x)."""
    tree = reuse_or_create_group(spec["correction_group"])
    ensure_interface(tree, CORRECTION_SOCKETS)
    curve = spec["curve"]
    nodes, links = tree.nodes, tree.links

    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)

    frame = new_frame(tree, "Gain frame", frame_label(curve))

    column = 0
    x_socket = clamped_roughness(
        tree, group_in, frame,
        "r = clamp(Roughness)" if curve["variable"] == "alpha" else "x = clamp(Roughness)")
    column += 1

    if curve["variable"] == "alpha":
        square = math_node(tree, "MULTIPLY", "x = alpha = r\u00b2",
                           (FRAME_INSET + COLUMN_STEP * column, 0.0), frame, "Square")
        links.new(x_socket, square.inputs[0])
        links.new(x_socket, square.inputs[1])
        x_socket = square.outputs[0]
        column += 1

    num_out, num_const, num_cols = horner_chain(
        tree, curve["numerator"], x_socket, column, 0.0, "num", frame)
    den_out, den_const, den_cols = horner_chain(
        tree, curve["denominator"], x_socket, column, -ROW_STEP, "den", frame)
    column += max(num_cols, den_cols)

    gain_out, column = gain_nodes(tree, frame, (num_out, num_const), (den_out, den_const),
                                  column)

    def col_x():
        return FRAME_INSET + COLUMN_STEP * column

    column += 1

    if params.get("color_model") == "physical":
        # C / (1 - C (1 - E_avg)) with E_avg = 1 / Gain: the albedo of a coloured
        # surface whose multiple bounces are tinted, Kulla and Conty's
        # C (E_avg + Fms (1 - E_avg)) / E_avg.
        chain = Chain(tree, frame, column=column, y=-ROW_STEP)
        lost = chain.math("SUBTRACT", "1 - E_avg = 1 - 1 / Gain", 1.0,
                          chain.math("DIVIDE", "E_avg = 1 / Gain", 1.0, gain_out))
        color = group_in.outputs["Color"]
        mix_out = chain.vector("DIVIDE", "C / (1 - C (1 - E_avg))", color,
                               chain.vector("SUBTRACT", "1 - C (1 - E_avg)", (1.0, 1.0, 1.0),
                                            chain.vector("SCALE", "C (1 - E_avg)", color, lost)),
                               name="Apply gain")
        column = chain.column + 1
    else:
        mix_out = apply_gain(tree, group_in.outputs["Color"], gain_out, (col_x() + 50.0, 0.0))

    group_out = nodes.new("NodeGroupOutput")
    group_out.location = (col_x() + 50.0 + COLUMN_STEP, 0.0)
    links.new(mix_out, group_out.inputs["Color"])
    links.new(gain_out, group_out.inputs["Gain"])

    description = group_description(spec, params, "correction")
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"]],
               asset_fields(params, "helper"))
    return tree


def build_shader_group(spec, params, correction_tree):
    """The group Color, Roughness, Normal -> BSDF: a Glossy BSDF whose colour
    goes through the correction group."""
    description = group_description(spec, params, "shader")
    return build_glossy_group(spec["shader_group"], spec, params, correction_tree, description,
                              ["gloffuse", spec["distribution"]])


def build_glossy_group(name, spec, params, correction_tree, description, tags, sockets=None):
    """Color, Roughness, Normal -> BSDF: a Glossy BSDF of the spec's distribution
    whose colour goes through `correction_tree` (roughness-only or view; every
    input the two share is passed on)."""
    tree = reuse_or_create_group(name)
    ensure_interface(tree, sockets or SHADER_SOCKETS)
    nodes, links = tree.nodes, tree.links

    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)

    correction = nodes.new("ShaderNodeGroup")
    correction.node_tree = correction_tree
    correction.name = "Brightness correction"
    correction.label = short_label(correction_tree.name)
    correction.width = 260.0
    correction.location = (COLUMN_STEP + 20.0, 160.0)
    for sock in correction.inputs:
        if sock.name in group_in.outputs:
            links.new(group_in.outputs[sock.name], sock)

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
    mark_asset(tree, description, tags, asset_fields(params, "shader"))
    return tree
