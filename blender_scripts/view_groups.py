# ---------------------------------------------------------------------------
# gloffuse view_groups.py: the view-dependent and multiple-scattering groups
# (spec["view"]): a correction group with Gain = 1 / E(mu, r), its shader
# group, and the multiscatter group Glossy + Diffuse(Color x (1 - E(mu, r))).
#
# The directional albedo E(mu, r) travels as a table in the parameters and is
# packed into the .blend as a 32-bit float OpenEXR image (R = B = A = E, G =
# E_avg(r)). An Image Texture node samples it at (u, v) = pixel centres of
# (r, mu), with mu the view cosine at the normal the BSDF really uses (the
# normal group of normal_group.py), so Cycles' linear interpolation
# reproduces the table exactly at its grid points.
#
# Colour (params["color_model"]): "exact" multiplies Color by 1 / E, so the
# surface's albedo is Color; "physical" tints the energy multiple bounces add
# as Kulla and Conty (and Blender's Multiscatter GGX) do:
# Fms = C E_avg / (1 - C (1 - E_avg)), colour C (1 + Fms (1 - E) / E).
#
# One part of the script the gloffuse binary concatenates: header, compat.py,
# params.py, nodes.py, roughness_groups.py, normal_group.py, view_groups.py, layered_groups.py, groups.py,
# runtime.py, then a main. Functions and constants only; the socket lists
# below extend roughness_groups.py's.
# ---------------------------------------------------------------------------
import bpy

def view_correction_sockets():
    """Roughness, Color, Normal [, Bump Map Correction] -> Color, Gain."""
    return CORRECTION_SOCKETS[:2] + [NORMAL_INPUT] + bump_map_correction_inputs() + [
        CORRECTION_SOCKETS[2],
        {"in_out": "OUTPUT", "name": "Gain", "type": "NodeSocketFloat",
         "description": "Brightness gain 1 / E(mu, r) of a white surface for this "
                        "roughness and view"},
    ]


def view_shader_sockets(output_description):
    """Color, Roughness, Normal [, Bump Map Correction] -> BSDF."""
    return SHADER_SOCKETS[:3] + bump_map_correction_inputs() + [
        {"in_out": "OUTPUT", "name": "BSDF", "type": "NodeSocketShader",
         "description": output_description},
    ]


def albedo_image(view):
    """The packed float image holding E(mu, r): reused by name, resized if needed.
    Row i is mu = i / (height - 1) (row 0 at the bottom, Blender's order), column
    j is r = j / (width - 1); E is stored in R, B and alpha, E_avg(r) in G
    (channel packed)."""
    table = view["table"]
    width, height = int(table["width"]), int(table["height"])
    values = finite_list(table["values"], "view.table.values")
    if len(values) != width * height:
        raise ValueError("view.table holds %d values, not %d x %d" % (len(values), width, height))
    average = finite_list(table["average"], "view.table.average")
    if len(average) != width:
        raise ValueError("view.table.average holds %d values, not %d" % (len(average), width))
    pixels = []
    for index, value in enumerate(values):
        pixels.extend((value, average[index % width], value, value))
    return packed_float_image(view["image"], width, height, pixels)


def packed_float_image(name, width, height, pixels):
    """A non-colour, channel-packed 32-bit float image packed into the .blend:
    reused by name (resized if needed) and filled with `pixels` (RGBA, bottom
    row first)."""
    image = bpy.data.images.get(name)
    if image is not None and tuple(image.size) != (width, height):
        image.scale(width, height)
    if image is None:
        image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    image.alpha_mode = "CHANNEL_PACKED"
    image.pixels.foreach_set(pixels)
    image.update()
    image.file_format = "OPEN_EXR"
    image.pack()
    return image


def albedo_lookup(tree, view, roughness_socket, mu_socket, x, frame):
    """Nodes that read E(mu, r) and E_avg(r) for the clamped roughness and the
    view cosine; x is the first column. Returns (E, E_avg, next column)."""
    nodes, links = tree.nodes, tree.links
    table = view["table"]
    width, height = int(table["width"]), int(table["height"])

    def at(column, y=0.0):
        return (FRAME_INSET + COLUMN_STEP * (x + column), y)

    # Pixel centres: u = r (W-1)/W + 1/(2W), clamped into the table.
    u = math_node(tree, "MULTIPLY_ADD", "u = r (W-1)/W + 1/2W", at(0), frame, "u")
    u.use_clamp = True
    links.new(roughness_socket, u.inputs[0])
    u.inputs[1].default_value = (width - 1.0) / width
    u.inputs[2].default_value = 0.5 / width
    v = math_node(tree, "MULTIPLY_ADD", "v = mu (H-1)/H + 1/2H", at(0, -ROW_STEP), frame, "v")
    v.use_clamp = True
    links.new(mu_socket, v.inputs[0])
    v.inputs[1].default_value = (height - 1.0) / height
    v.inputs[2].default_value = 0.5 / height
    uv = nodes.new("ShaderNodeCombineXYZ")
    uv.name = "uv"
    set_parent(uv, frame)
    uv.location = at(1)
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
    texture.location = at(2)
    links.new(uv.outputs[0], texture.inputs["Vector"])
    channels = nodes.new("ShaderNodeSeparateXYZ")
    channels.name = "E_avg(r)"
    channels.label = "G = E_avg(r)"
    set_parent(channels, frame)
    channels.location = at(3, -ROW_STEP)
    links.new(texture.outputs["Color"], channels.inputs[0])
    return texture.outputs["Alpha"], channels.outputs["Y"], x + 4


def view_cosine(tree, params, group_in, x, frame):
    """The normal group's node, fed by the group's Normal: returns the view
    cosine at the normal the BSDF shades with."""
    normal_tree = bpy.data.node_groups[params["normal_group"]]
    node = normal_group_node(tree, normal_tree, group_in, (FRAME_INSET + COLUMN_STEP * x, -ROW_STEP), frame)
    return node.outputs["View Cosine"]


def tinted_energy(chain, color, e_avg):
    """Fms = C E_avg / (1 - C (1 - E_avg)), per channel (Kulla and Conty's
    multiple-scattering colour, as Cycles' Multiscatter GGX computes it)."""
    lost = chain.math("SUBTRACT", "1 - E_avg", 1.0, e_avg)
    den = chain.vector("SUBTRACT", "1 - C (1 - E_avg)", (1.0, 1.0, 1.0),
                       chain.vector("SCALE", "C (1 - E_avg)", color, lost))
    return chain.vector("DIVIDE", "Fms = C E_avg / (1 - C (1 - E_avg))",
                        chain.vector("SCALE", "C E_avg", color, e_avg), den)


def glossy_plus_diffuse(tree, spec, group_in, glossy_color, diffuse_color, x, labels):
    """Glossy BSDF (the spec's distribution; the group's Roughness and Normal) of
    colour glossy_color, plus a Diffuse BSDF of colour diffuse_color (the group's
    Normal), into the group's BSDF output; nodes from column x on, labelled
    (glossy, diffuse, add)."""
    nodes, links = tree.nodes, tree.links
    glossy_label, diffuse_label, add_label = labels
    glossy = glossy_node(nodes, spec["distribution"])
    glossy.name = "Glossy BSDF"
    glossy.label = short_label(glossy_label)
    glossy.width = NODE_WIDTH
    glossy.location = (x, 200.0)
    links.new(glossy_color, glossy.inputs["Color"])
    links.new(group_in.outputs["Roughness"], glossy.inputs["Roughness"])
    links.new(group_in.outputs["Normal"], glossy.inputs["Normal"])
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.name = "Diffuse BSDF"
    diffuse.label = diffuse_label
    diffuse.width = NODE_WIDTH
    diffuse.location = (x, -ROW_STEP)
    links.new(diffuse_color, diffuse.inputs["Color"])
    links.new(group_in.outputs["Normal"], diffuse.inputs["Normal"])
    add = nodes.new("ShaderNodeAddShader")
    add.name = add_label
    add.location = (x + COLUMN_STEP, 0.0)
    links.new(glossy.outputs[0], add.inputs[0])
    links.new(diffuse.outputs[0], add.inputs[1])
    group_out = nodes.new("NodeGroupOutput")
    group_out.location = (x + 2 * COLUMN_STEP, 0.0)
    links.new(add.outputs[0], group_out.inputs["BSDF"])


def build_view_correction_group(spec, params):
    """Roughness, Color, Normal -> Color, Gain with Gain = 1 / E(mu, r)."""
    view = spec["view"]
    tree = reuse_or_create_group(view["correction_group"])
    ensure_interface(tree, view_correction_sockets())
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    physical = params.get("color_model") == "physical"
    frame = new_frame(tree, "Albedo frame", "Gain = 1 / E(mu, r), mu at the shaded normal")
    r = clamped_roughness(tree, group_in, frame)
    mu = view_cosine(tree, params, group_in, 1, frame)
    albedo, e_avg, column = albedo_lookup(tree, view, r, mu, 2, frame)
    gain = math_node(tree, "DIVIDE", "Gain = 1 / E", (FRAME_INSET + COLUMN_STEP * column + 100.0, 0.0),
                     frame, "Gain")
    gain.inputs[0].default_value = 1.0
    links.new(albedo, gain.inputs[1])
    x_end = FRAME_INSET + COLUMN_STEP * (column + 1) + 150.0
    if physical:
        chain = Chain(tree, frame, column=column + 1, y=-ROW_STEP)
        color = group_in.outputs["Color"]
        fms = tinted_energy(chain, color, e_avg)
        ratio = chain.math("DIVIDE", "(1 - E) / E", chain.math("SUBTRACT", "1 - E", 1.0, albedo), albedo)
        factor = chain.vector("ADD", "1 + Fms (1 - E) / E", (1.0, 1.0, 1.0),
                              chain.vector("SCALE", "Fms (1 - E) / E", fms, ratio))
        color_out = chain.vector("MULTIPLY", "Color (1 + Fms (1 - E) / E)", color, factor,
                                 name="Apply gain")
        x_end = FRAME_INSET + COLUMN_STEP * (chain.column + 1) + 150.0
    else:
        mix, color_a, color_b, color_out = multiply_color_node(nodes)
        mix.name = "Apply gain"
        mix.label = "Color × Gain"
        mix.width = NODE_WIDTH
        mix.location = (x_end, 0.0)
        links.new(group_in.outputs["Color"], color_a)
        links.new(gain.outputs[0], color_b)
    group_out = nodes.new("NodeGroupOutput")
    group_out.location = (x_end + COLUMN_STEP, 0.0)
    links.new(color_out, group_out.inputs["Color"])
    links.new(gain.outputs[0], group_out.inputs["Gain"])
    colour = (
        "Color is multiplied by 1 + Fms (1 - E) / E with Fms = C E_avg / (1 - C (1 - E_avg)): "
        "the energy multiple bounces add is tinted by the colour, as in Blender's "
        "Multiscatter GGX, so a rough coloured surface comes out darker and more saturated "
        "than Color." if physical else
        "Color is multiplied by Gain, so the surface's albedo is exactly Color.")
    description = description_text(spec, params, (
        "View-dependent brightness gain for Blender's %s Glossy BSDF: Gain = 1 / E(mu, r), "
        "with mu = N' · I at the normal the BSDF really shades with (Normal, raised as Cycles "
        "raises it; see '%s') and E read from the packed table '%s', so every pixel of an "
        "evenly lit white surface is 100 %%. %s"
        % (spec["distribution"], params["normal_group"], view["image"], colour)))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "view"],
               asset_fields(params, "helper"))
    return tree


def build_view_shader_group(spec, params, correction_tree):
    """Color, Roughness, Normal -> BSDF: Glossy with colour x 1 / E(mu, r)."""
    description = description_text(spec, params, (
        "Glossy BSDF (%s) whose colour is multiplied by the view-dependent gain of '%s'."
        % (spec["distribution"], correction_tree.name)))
    return build_glossy_group(spec["view"]["shader_group"], spec, params, correction_tree,
                              description,
                              ["gloffuse", spec["distribution"], "view"],
                              view_shader_sockets("Brightness-corrected glossy BSDF"))


def build_multiscatter_group(spec, params):
    """Color, Roughness, Normal -> BSDF: Glossy(Color) + Diffuse(Color x (1 - E(mu, r)))
    (physical colour: Diffuse(Color x Fms x (1 - E))): the energy single
    scattering loses comes back as a diffuse-like lobe."""
    view = spec["view"]
    tree = reuse_or_create_group(view["multiscatter_group"])
    ensure_interface(tree, view_shader_sockets(
        "Glossy BSDF plus a diffuse lobe carrying the energy it loses"))
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    physical = params.get("color_model") == "physical"
    frame = new_frame(tree, "Albedo frame", "Lost energy 1 - E(mu, r), mu at the shaded normal")
    r = clamped_roughness(tree, group_in, frame)
    mu = view_cosine(tree, params, group_in, 1, frame)
    albedo, e_avg, column = albedo_lookup(tree, view, r, mu, 2, frame)
    x = FRAME_INSET + COLUMN_STEP * column + 100.0
    lost = math_node(tree, "SUBTRACT", "1 - E", (x, 0.0), frame, "Lost")
    lost.inputs[0].default_value = 1.0
    links.new(albedo, lost.inputs[1])
    color = group_in.outputs["Color"]
    if physical:
        chain = Chain(tree, frame, column=column + 1, y=-ROW_STEP)
        diffuse_color = chain.vector("SCALE", "Color Fms (1 - E)",
                                     chain.vector("MULTIPLY", "Color Fms", color,
                                                  tinted_energy(chain, color, e_avg)),
                                     lost.outputs[0], name="Diffuse colour")
        x = FRAME_INSET + COLUMN_STEP * chain.column
    else:
        mix, color_a, color_b, diffuse_color = multiply_color_node(nodes)
        mix.name = "Diffuse colour"
        mix.label = "Color × (1 - E)"
        mix.width = NODE_WIDTH
        mix.location = (x + COLUMN_STEP, -ROW_STEP)
        links.new(color, color_a)
        links.new(lost.outputs[0], color_b)
    glossy_plus_diffuse(tree, spec, group_in, color, diffuse_color, x + 2 * COLUMN_STEP,
                        ("Glossy BSDF (%s)" % spec["distribution"], "Diffuse BSDF", "Add"))
    description = description_text(spec, params, (
        "Glossy BSDF (%s) plus a diffuse lobe of colour %s: the energy single scattering "
        "loses comes back, so an evenly lit white surface is 100 %% at every pixel without "
        "brightening the highlight. mu is read at the normal the glossy BSDF shades with (see '%s')."
        % (spec["distribution"],
           "Color × Fms × (1 - E(mu, r)), Fms = C E_avg / (1 - C (1 - E_avg)) (physical colour)"
           if physical else "Color × (1 - E(mu, r))", params["normal_group"])))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "multiscatter"],
               asset_fields(params, "shader"))
    return tree
