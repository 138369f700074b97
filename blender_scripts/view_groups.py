# ---------------------------------------------------------------------------
# gloffuse view_groups.py: the view-dependent and multiple-scattering groups
# (spec["view"]): a correction group with Gain = 1 / E(mu, r), its shader
# group, and the multiscatter group Glossy + Diffuse(Color x (1 - E(mu, r))).
#
# The directional albedo E(mu, r) travels as a table in the parameters and is
# packed into the .blend as a 32-bit float OpenEXR image. An Image Texture node
# samples it at (u, v) = pixel centres of (r, mu), with mu = N.I from the
# Geometry node, so Cycles' linear interpolation reproduces the table exactly
# at its grid points.
#
# One part of the script the gloffuse binary concatenates: header, compat.py,
# params.py, nodes.py, roughness_groups.py, view_groups.py, groups.py,
# runtime.py, then a main. Functions and constants only; the socket lists
# below extend roughness_groups.py's.
# ---------------------------------------------------------------------------
import bpy

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
    values = finite_list(table["values"], "view.table.values")
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


def build_view_correction_group(spec, params):
    """Roughness, Color -> Color, Gain with Gain = 1 / E(mu, r)."""
    view = spec["view"]
    tree = reuse_or_create_group(view["correction_group"])
    ensure_interface(tree, VIEW_CORRECTION_SOCKETS)
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    frame = new_frame(tree, "Albedo frame", "Gain = 1 / E(mu, r), mu = N · I")
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
    description = description_text(spec, params, (
        "View-dependent brightness gain for Blender's %s Glossy BSDF: Gain = 1 / E(mu, r), "
        "with mu = N · I from the Geometry node and E read from the packed table '%s', "
        "so every pixel of an evenly lit white surface is 100 %%." % (spec["distribution"], view["image"])))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "view"])
    return tree


def build_view_shader_group(spec, params, correction_tree):
    """Color, Roughness, Normal -> BSDF: Glossy with colour x 1 / E(mu, r)."""
    description = description_text(spec, params, (
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
    frame = new_frame(tree, "Albedo frame", "Lost energy 1 - E(mu, r), mu = N · I")
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
    description = description_text(spec, params, (
        "Glossy BSDF (%s) plus a diffuse lobe of colour Color × (1 - E(mu, r)): the "
        "energy single scattering loses comes back, so an evenly lit white surface is 100 %% "
        "at every pixel without brightening the highlight." % spec["distribution"]))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "multiscatter"])
    return tree
