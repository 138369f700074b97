# ---------------------------------------------------------------------------
# gloffuse view_groups.py: the view-dependent and multiple-scattering groups
# (spec["view"]): a correction group with Gain = 1 / E(mu, r), its shader
# group, and the multiscatter group Glossy + Diffuse(Color x (1 - E(mu, r))).
#
# The directional albedo E(mu, r) travels as a table in the parameters and is
# packed into the .blend as a 32-bit float OpenEXR image, one pixel per cell of
# the table holding the cell's four corners, plus a row for E_avg(r). The group
# reads the cell (r, mu) falls in with Closest interpolation and interpolates
# bilinearly in Math nodes, with mu the view cosine at the normal the BSDF
# really uses (the normal group of normal_group.py): Cycles and EEVEE read the
# same numbers, the table's own at its grid points.
#
# Colour (params["color_model"]): "exact" multiplies Color by 1 / E, so the
# surface's albedo is Color; "physical" tints the energy multiple bounces add
# as Kulla and Conty (and Blender's Multiscatter GGX) do:
# Fms = C E_avg / (1 - C (1 - E_avg)), colour C (1 + Fms (1 - E) / E).
#
# A module of the gloffuse_blender package. Functions and constants only; the socket lists
# below extend roughness_groups.py's.
# ---------------------------------------------------------------------------
import bpy

from .compat import glossy_node, mark_asset, multiply_color_node, set_parent, set_tree_description
from .nodes import (
    COLUMN_STEP,
    FRAME_INSET,
    NODE_WIDTH,
    ROW_STEP,
    Chain,
    apply_gain,
    asset_fields,
    clamped_roughness,
    description_text,
    ensure_interface,
    math_node,
    new_frame,
    reuse_or_create_group,
    short_label,
)
from .normal_group import NORMAL_INPUT, bump_map_correction_inputs, is_eevee, normal_group_node
from .params import finite_list
from .roughness_groups import CORRECTION_SOCKETS, SHADER_SOCKETS, build_glossy_group

def view_correction_sockets(spec):
    """Roughness, Color, Normal [, Bump Map Correction] -> Color, Gain."""
    return CORRECTION_SOCKETS[:2] + [NORMAL_INPUT] + bump_map_correction_inputs(spec) + [
        CORRECTION_SOCKETS[2],
        {"in_out": "OUTPUT", "name": "Gain", "type": "NodeSocketFloat",
         "description": "Brightness gain 1 / E(mu, r) of a white surface for this "
                        "roughness and view"},
    ]


def view_shader_sockets(spec, output_description):
    """Color, Roughness, Normal [, Bump Map Correction] -> BSDF."""
    return SHADER_SOCKETS[:3] + bump_map_correction_inputs(spec) + [
        {"in_out": "OUTPUT", "name": "BSDF", "type": "NodeSocketShader",
         "description": output_description},
    ]


def corner_cells(value_at, rows, columns):
    """RGBA pixels (bottom row first) of a table of rows x columns samples
    packed by cell: pixel (i, j) of the (columns - 1) x (rows - 1) image holds
    the corners of cell (i, j), (v[i][j], v[i][j+1], v[i+1][j], v[i+1][j+1]),
    so one unfiltered read gives everything its bilinear interpolation needs."""
    pixels = []
    for i in range(rows - 1):
        for j in range(columns - 1):
            pixels.extend((value_at(i, j), value_at(i, j + 1),
                           value_at(i + 1, j), value_at(i + 1, j + 1)))
    return pixels


def albedo_image(view):
    """The packed float image holding E(mu, r): reused by name, resized if needed.
    Row i < height - 1 holds the cells between mu = i / (height - 1) and
    (i + 1) / (height - 1) (see corner_cells), column j those between
    r = j / (width - 1) and (j + 1) / (width - 1); the top row holds E_avg(r)
    the same way: (E_avg(r_j), E_avg(r_j+1), E_avg(r_j), E_avg(r_j+1))."""
    table = view["table"]
    width, height = int(table["width"]), int(table["height"])
    values = finite_list(table["values"], "view.table.values")
    if len(values) != width * height:
        raise ValueError("view.table holds %d values, not %d x %d" % (len(values), width, height))
    average = finite_list(table["average"], "view.table.average")
    if len(average) != width:
        raise ValueError("view.table.average holds %d values, not %d" % (len(average), width))
    pixels = corner_cells(lambda i, j: values[i * width + j], height, width)
    pixels += corner_cells(lambda i, j: average[j], 2, width)
    return packed_float_image(view["image"], width - 1, height, pixels)


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


def grid_cell(chain, coordinate, samples, name):
    """Where `coordinate` (clamped to [0, 1]) falls on a grid of `samples`
    points over [0, 1]: the cell k = min(floor(x), N - 2) with x = c (N - 1),
    and the fraction x - k in [0, 1] across it."""
    x = chain.clamp("%s (N-1), N = %d" % (name, samples),
                    chain.math("MULTIPLY", "%s (N-1)" % name, coordinate, samples - 1.0),
                    0.0, samples - 1.0)
    cell = chain.math("MINIMUM", "%s cell = min(floor, N-2)" % name,
                      chain.math("FLOOR", "floor %s (N-1)" % name, x), samples - 2.0)
    return cell, chain.math("SUBTRACT", "%s fraction" % name, x, cell)


def read_cell(chain, image, column, row, label):
    """The four corners stored in pixel (column, row) of a corner-packed image
    (see corner_cells), read at the pixel's centre with Closest interpolation:
    every engine reads that exactly, whereas EEVEE filters Linear through
    mipmaps picked by the screen-space derivative of the lookup, which blurs a
    table read at the view cosine (5 % off at the rim of a 64 px sphere)."""
    width, height = image.size
    u = chain.math("MULTIPLY_ADD", "u = (column + 1/2) / W", column, 1.0 / width, 0.5 / width)
    v = chain.math("MULTIPLY_ADD", "v = (row + 1/2) / H", row, 1.0 / height, 0.5 / height)
    nodes, links = chain.tree.nodes, chain.tree.links
    x, y = FRAME_INSET + COLUMN_STEP * (chain.column + 1), chain.y
    uv = nodes.new("ShaderNodeCombineXYZ")
    uv.name = "uv: " + label
    set_parent(uv, chain.frame)
    uv.location = (x, y)
    links.new(u, uv.inputs["X"])
    links.new(v, uv.inputs["Y"])
    texture = nodes.new("ShaderNodeTexImage")
    texture.name = label
    texture.label = short_label("%s, %d x %d cells" % (label, width, height))
    texture.image = image
    texture.interpolation = "Closest"
    texture.extension = "EXTEND"
    texture.width = 240.0
    set_parent(texture, chain.frame)
    texture.location = (x + COLUMN_STEP, y)
    links.new(uv.outputs[0], texture.inputs["Vector"])
    corners = nodes.new("ShaderNodeSeparateXYZ")
    corners.name = "corners: " + label
    corners.label = "corners (R, G, B; A)"
    set_parent(corners, chain.frame)
    corners.location = (x + 2 * COLUMN_STEP + 100.0, y)
    links.new(texture.outputs["Color"], corners.inputs[0])
    chain.skip(4)
    return (corners.outputs["X"], corners.outputs["Y"], corners.outputs["Z"],
            texture.outputs["Alpha"])


def bilinear(chain, corners, across, up, label):
    """Bilinear interpolation of a cell's corners (v00, v01, v10, v11) at
    fractions `across` (second index) and `up` (first index)."""
    v00, v01, v10, v11 = corners
    lower = chain.mix_value(label + " lower", across, v00, v01)
    upper = chain.mix_value(label + " upper", across, v10, v11)
    return chain.mix_value(label, up, lower, upper)


def albedo_lookup(tree, view, roughness_socket, mu_socket, x, frame, average=False):
    """Nodes that read E(mu, r) (and, if `average`, E_avg(r)) for the clamped
    roughness and the view cosine; x is the first column. Returns (E, E_avg or
    None, next column)."""
    table = view["table"]
    width, height = int(table["width"]), int(table["height"])
    image = albedo_image(view)
    chain = Chain(tree, frame, column=x)
    column, across = grid_cell(chain, roughness_socket, width, "r")
    row, up = grid_cell(chain, mu_socket, height, "mu")
    e = bilinear(chain, read_cell(chain, image, column, row, "E(mu, r)"), across, up, "E(mu, r)")
    e_avg = None
    if average:
        # The top row: E_avg at the cell's two roughness values.
        low, high, _, _ = read_cell(chain, image, column, height - 1.0, "E_avg(r)")
        e_avg = chain.mix_value("E_avg(r)", across, low, high)
    return e, e_avg, chain.column + 1


def view_cosine(tree, spec, group_in, x, frame):
    """The spec's normal group's node, fed by the group's Normal: returns the
    view cosine at the normal the BSDF shades with."""
    normal_tree = bpy.data.node_groups[spec["normal_group"]]
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


def physical_color(chain, color, albedo, e_avg):
    """The physical colour model's colour C (1 + Fms (1 - E) / E): the energy
    multiple bounces add, tinted (tinted_energy). The node is named "Apply gain"."""
    fms = tinted_energy(chain, color, e_avg)
    ratio = chain.math("DIVIDE", "(1 - E) / E", chain.math("SUBTRACT", "1 - E", 1.0, albedo), albedo)
    factor = chain.vector("ADD", "1 + Fms (1 - E) / E", (1.0, 1.0, 1.0),
                          chain.vector("SCALE", "Fms (1 - E) / E", fms, ratio))
    return chain.vector("MULTIPLY", "Color (1 + Fms (1 - E) / E)", color, factor,
                        name="Apply gain")


def glossy_plus_diffuse(tree, spec, group_in, glossy_color, diffuse_color, x, labels):
    """Glossy BSDF (the spec's distribution; the group's Roughness and Normal) of
    colour glossy_color, plus a Diffuse BSDF of colour diffuse_color (the group's
    Normal), into the group's BSDF output; nodes from column x on, labelled
    (glossy, diffuse, add)."""
    glossy_label, diffuse_label, add_label = labels
    glossy = glossy_node(tree.nodes, spec["distribution"])
    glossy.name = "Glossy BSDF"
    glossy.label = short_label(glossy_label)
    glossy.width = NODE_WIDTH
    glossy.location = (x, 200.0)
    tree.links.new(glossy_color, glossy.inputs["Color"])
    tree.links.new(group_in.outputs["Roughness"], glossy.inputs["Roughness"])
    tree.links.new(group_in.outputs["Normal"], glossy.inputs["Normal"])
    shader_plus_diffuse(tree, group_in, glossy.outputs[0], diffuse_color, x,
                        (diffuse_label, add_label))


def shader_plus_diffuse(tree, group_in, shader, diffuse_color, x, labels):
    """`shader` plus a Diffuse BSDF of colour diffuse_color (the group's Normal)
    into the group's BSDF output; nodes from column x on, labelled (diffuse, add)."""
    nodes, links = tree.nodes, tree.links
    diffuse_label, add_label = labels
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
    links.new(shader, add.inputs[0])
    links.new(diffuse.outputs[0], add.inputs[1])
    group_out = nodes.new("NodeGroupOutput")
    group_out.location = (x + 2 * COLUMN_STEP, 0.0)
    links.new(add.outputs[0], group_out.inputs["BSDF"])


def build_view_correction_group(spec, params):
    """Roughness, Color, Normal -> Color, Gain with Gain = 1 / E(mu, r)."""
    view = spec["view"]
    tree = reuse_or_create_group(view["correction_group"])
    ensure_interface(tree, view_correction_sockets(spec))
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    physical = params.get("color_model") == "physical"
    frame = new_frame(tree, "Albedo frame", "Gain = 1 / E(mu, r), mu at the shaded normal")
    r = clamped_roughness(tree, group_in, frame)
    mu = view_cosine(tree, spec, group_in, 1, frame)
    albedo, e_avg, column = albedo_lookup(tree, view, r, mu, 2, frame, average=physical)
    gain = math_node(tree, "DIVIDE", "Gain = 1 / E", (FRAME_INSET + COLUMN_STEP * column + 100.0, 0.0),
                     frame, "Gain")
    gain.inputs[0].default_value = 1.0
    links.new(albedo, gain.inputs[1])
    x_end = FRAME_INSET + COLUMN_STEP * (column + 1) + 150.0
    if physical:
        chain = Chain(tree, frame, column=column + 1, y=-ROW_STEP)
        color_out = physical_color(chain, group_in.outputs["Color"], albedo, e_avg)
        x_end = FRAME_INSET + COLUMN_STEP * (chain.column + 1) + 150.0
    else:
        color_out = apply_gain(tree, group_in.outputs["Color"], gain.outputs[0], (x_end, 0.0))
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
        "with mu = N' · I at the normal the BSDF really shades with (Normal, %s; see '%s') "
        "and E read from the packed table '%s', so every pixel of an evenly lit white surface "
        "is 100 %%. %s"
        % (spec["distribution"],
           "as EEVEE takes it" if is_eevee(spec) else "raised as Cycles raises it",
           spec["normal_group"], view["image"], colour)))
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
                              view_shader_sockets(spec, "Brightness-corrected glossy BSDF"))


def build_multiscatter_group(spec, params):
    """Color, Roughness, Normal -> BSDF: Glossy(Color) + Diffuse(Color x (1 - E(mu, r)))
    (physical colour: Diffuse(Color x Fms x (1 - E))): the energy single
    scattering loses comes back as a diffuse-like lobe."""
    view = spec["view"]
    tree = reuse_or_create_group(view["multiscatter_group"])
    ensure_interface(tree, view_shader_sockets(
        spec, "Glossy BSDF plus a diffuse lobe carrying the energy it loses"))
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    physical = params.get("color_model") == "physical"
    frame = new_frame(tree, "Albedo frame", "Lost energy 1 - E(mu, r), mu at the shaded normal")
    r = clamped_roughness(tree, group_in, frame)
    mu = view_cosine(tree, spec, group_in, 1, frame)
    albedo, e_avg, column = albedo_lookup(tree, view, r, mu, 2, frame, average=physical)
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
           if physical else "Color × (1 - E(mu, r))", spec["normal_group"])))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "multiscatter"],
               asset_fields(params, "shader"))
    return tree
