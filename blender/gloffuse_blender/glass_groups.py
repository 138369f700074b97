# ---------------------------------------------------------------------------
# gloffuse glass_groups.py: "Gloffuse Glass (...)" and "Gloffuse Refraction
# (...)", Blender's own Glass and Refraction BSDFs whose colour is divided by
# E(mu, r, eta), the albedo of one rough dielectric interface (spec["glass"]).
#
# A rough interface returns less light than meets it: the part its single
# microfacet bounce misses. E is that part's complement, computed by gloffuse
# for exactly the BSDF this Blender renders (3.0-3.4: two closures weighted
# by the Fresnel at the normal; 3.6 on: one closure with the Fresnel of each
# microfacet). eta is the index beyond the surface over the index before it:
# IOR on a front face (light entering), 1 / IOR on a back face (light leaving,
# where Cycles shades the inside of the glass). With colour Color / E every
# interface returns Color of what meets it, entering and leaving, so a white
# solid glass object in an evenly lit white world is 100 % bright.
#
# E travels as packed float images laid out as the layered groups' coat
# table (layered_groups.py's slice_image), entering and leaving; the group
# reads both sides at (mu, r, IOR) and takes the one its face needs (Geometry
# > Backfacing). In 3.0-3.5 the Glass node's E is F R + max(1e-4, 1 - F) T
# with the Fresnel F at the normal (a Fresnel node, exact where it jumps at
# the critical angle) and the lobes' R and T from the tables. The tables'
# rows are over t = mu^(2/3), crowded at grazing where E falls about as
# sqrt(mu); the leaving refraction lobe's are over s, crowded from both sides
# at the critical cosine mu_c = sqrt(1 - 1 / n^2), where that lobe falls
# from most of the light to almost none (gloffuse's critical_crowded):
# mu = mu_c + (1 - mu_c) (2s - 1)^2 above it, mu_c - mu_c (1 - 2s)^2 below.
# mu comes from the shading-normal group (normal_group.py).
#
# Where Blender itself keeps the light, the group is Blender's own: in 3.0-3.5
# the GGX Glass group is the Multiscatter GGX Glass BSDF, a random walk that
# returns every bit of light with about a thousandth of the gain's noise in a
# rough dense sphere (glass_table["glass_group"] == "multiscatter"; the tables
# then carry nothing for the Glass node). Its colour is the walk's: light that
# bounces k times among the microfacets is tinted k times.
#
# Colour (params["color_model"]): "exact" gives the node Color / E, so every
# interface returns Color of what meets it; "physical" gives it
# Color (1 + Fms (1 - E) / E) with Fms = C E_avg / (1 - C (1 - E_avg)) and
# E_avg(r, eta) the side's average (tables laid out as E's, every row alike),
# tinting the light the microfacets bounce more than once, as Blender 4.x's
# Multiscatter GGX glass does with its Color. White glass is the same in both.
#
# A module of the gloffuse_blender package. Functions and constants only.
# ---------------------------------------------------------------------------
from .compat import mark_asset, set_parent, set_tree_description
from .layered_groups import clamped_ior, ior_input, slice_cell, slice_image, slice_read
from .nodes import (
    COLUMN_STEP,
    FRAME_INSET,
    ROW_STEP,
    Chain,
    asset_fields,
    clamped_roughness,
    description_text,
    ensure_interface,
    colored_bsdf,
    gained_bsdf,
    new_frame,
    reuse_or_create_group,
)
from .normal_group import NORMAL_INPUT, bump_map_correction_inputs
from .view_groups import grid_cell, physical_color, view_cosine

# Which Blender node each group wraps, and what it is.
GLASS_NODES = {
    "glass": ("ShaderNodeBsdfGlass", "Glass BSDF", "reflection and refraction"),
    "refraction": ("ShaderNodeBsdfRefraction", "Refraction BSDF", "refraction only"),
}


def glass_sockets(glass):
    """Color, Roughness, IOR, Normal [, Bump Map Correction] -> BSDF."""
    return [
        {"in_out": "INPUT", "name": "Color", "type": "NodeSocketColor",
         "default": (1.0, 1.0, 1.0, 1.0), "description": "Colour of the glass"},
        {"in_out": "INPUT", "name": "Roughness", "type": "NodeSocketFloat", "subtype": "FACTOR",
         "default": 0.5, "min": 0.0, "max": 1.0, "description": "Roughness (0..1)"},
        ior_input(glass["table"], "Index of refraction of the glass (the back faces are its inside)"),
        NORMAL_INPUT,
    ] + bump_map_correction_inputs(glass["spec"]) + [
        {"in_out": "OUTPUT", "name": "BSDF", "type": "NodeSocketShader",
         "description": "Rough dielectric that returns all the light meeting it, both ways"},
    ]


def glass_image(glass, node, side, what=None):
    """The packed float image of E (or with `what` "average", of E_avg) for
    `node` ("glass" or "refraction") and `side` ("entering" or "leaving"; the
    two-closure glass's reflection lobe is two_closure_albedo's)."""
    key = "_".join(filter(None, (node, what, side)))
    return slice_image(glass["table"], key, "%s %s" % (glass["image"], key.replace("_", " ")),
                       "glass.table")


def around_critical(chain, cell, table, mu, n):
    """The cell of the leaving refraction table, whose rows are over s about
    the critical cosine mu_c = sqrt(1 - 1 / n^2): s = 1/2 + d / 2 above it and
    1/2 - d / 2 below, d = sqrt(|mu - mu_c| / (1 - mu_c or mu_c)) (gloffuse's
    critical_crowded): `cell` (slice_cell) with its row and fraction for s."""
    critical = chain.math("SQRT", "mu_c = sqrt(1 - 1/n^2)",
                          chain.math("SUBTRACT", "1 - 1/n^2", 1.0,
                                     chain.math("DIVIDE", "1/n^2", 1.0,
                                                chain.math("MULTIPLY", "n^2", n, n))))
    above = chain.math("GREATER_THAN", "above = mu > mu_c", mu, critical)
    # The side's span: 1 - mu_c above, mu_c below (a Math node divides by 0 to 0).
    span = chain.math("MULTIPLY_ADD", "span = mu_c + above (1 - 2 mu_c)", above,
                      chain.math("MULTIPLY_ADD", "1 - 2 mu_c", critical, -2.0, 1.0), critical)
    offset = chain.math("SUBTRACT", "mu - mu_c", mu, critical)
    d = chain.math("SQRT", "d = sqrt(|mu - mu_c| / span)",
                   chain.math("DIVIDE", "|mu - mu_c| / span",
                              chain.math("ABSOLUTE", "|mu - mu_c|", offset), span))
    s = chain.math("MULTIPLY_ADD", "s = 1/2 + sign(mu - mu_c) d / 2",
                   chain.math("SIGN", "sign(mu - mu_c)", offset),
                   chain.math("MULTIPLY", "d / 2", d, 0.5), 0.5)
    row, up = grid_cell(chain, s, int(table["size"]), "s")
    first, second, _, across, _, t = cell
    return first, second, row, across, up, t


def two_closure_albedo(tree, chain, glass, group_in, cell, n, refracted, frame):
    """Blender 3.0-3.5's Glass is two closures weighted by the Fresnel at the
    normal F: E = F R + max(1e-4, 1 - F) T, R the reflection lobe's albedo
    (read from the table), T the refraction lobe's (`refracted`). F comes from
    a Fresnel node, which takes 1 / IOR on a back face as the closures do; in
    a table over mu it would blur where it jumps to 1 at the critical angle."""
    reflection = slice_image(glass["table"], "reflection", "%s reflection" % glass["image"],
                             "glass.table")
    reflected = slice_read(chain, reflection, cell, "R")
    fresnel = tree.nodes.new("ShaderNodeFresnel")
    fresnel.name = "Fresnel at the normal"
    set_parent(fresnel, frame)
    fresnel.location = (FRAME_INSET, -3 * ROW_STEP)
    tree.links.new(n, fresnel.inputs["IOR"])
    tree.links.new(group_in.outputs["Normal"], fresnel.inputs["Normal"])
    f = fresnel.outputs["Fac"]
    weight = chain.math("MAXIMUM", "max(1e-4, 1 - F)", chain.math("SUBTRACT", "1 - F", 1.0, f),
                        1e-4)
    return chain.math("MULTIPLY_ADD", "E = F R + max(1e-4, 1 - F) T", f, reflected,
                      chain.math("MULTIPLY", "max(1e-4, 1 - F) T", weight, refracted))


def build_glass_group(spec, params, node):
    """Color, Roughness, IOR, Normal -> BSDF: Blender's `node` ("glass" or
    "refraction") of colour Color / E(mu, r, eta), or Blender's own
    Multiscatter GGX glass where that keeps the light."""
    glass = spec["glass"]
    tree = reuse_or_create_group(glass["%s_group" % node])
    ensure_interface(tree, glass_sockets(dict(glass, spec=spec)))
    group_in = tree.nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    if node == "glass" and glass["table"].get("glass_group") == "multiscatter":
        description = multiscatter_glass(tree, spec, params, group_in)
    else:
        description = gained_glass(tree, spec, params, group_in, node)
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "glass"],
               asset_fields(params, "shader"))
    return tree


def multiscatter_glass(tree, spec, params, group_in):
    """The group as Blender 3.0-3.5's Multiscatter GGX Glass BSDF (a random
    walk that keeps all the light), its inputs passed through; its
    description."""
    kind, label, _ = GLASS_NODES["glass"]
    bsdf = tree.nodes.new(kind)
    bsdf.name = label
    bsdf.distribution = "MULTI_GGX"
    for socket in ("Roughness", "IOR", "Normal"):
        tree.links.new(group_in.outputs[socket], bsdf.inputs[socket])
    colored_bsdf(tree, group_in.outputs["Color"], bsdf, 0.0)
    return description_text(spec, params, (
        "Blender's Multiscatter GGX Glass BSDF (reflection and refraction), which in this "
        "Blender is a random walk over the microfacets that returns all the light meeting "
        "it, entering and leaving: a white solid glass object in an evenly lit white world "
        "is 100 % bright, with far less noise than a gain on the single-scatter GGX glass. "
        "Its colour tints light once per bounce among the microfacets. Cycles only."))


def gained_glass(tree, spec, params, group_in, node):
    """The group as Blender's `node` of colour Color / E(mu, r, eta) (or the
    physical colour), E read from the tables; its description."""
    glass = spec["glass"]
    kind, label, what = GLASS_NODES[node]
    nodes, links = tree.nodes, tree.links
    frame = new_frame(tree, "Albedo frame",
                      "Gain = 1 / E(mu, r, eta): eta = IOR on a front face, 1 / IOR on a back face")
    r = clamped_roughness(tree, group_in, frame)
    mu = view_cosine(tree, spec, group_in, 1, frame)
    geometry = nodes.new("ShaderNodeNewGeometry")
    geometry.name = "Geometry"
    set_parent(geometry, frame)
    geometry.location = (FRAME_INSET, -2 * ROW_STEP)
    chain = Chain(tree, frame, column=2, y=0.0)
    table = glass["table"]
    n = clamped_ior(table, chain, group_in.outputs["IOR"])
    cell, _ = slice_cell(table, chain, r, chain.math("POWER", "t = mu^(2/3)", mu, 2.0 / 3.0), n)
    two_closures = node == "glass" and table.get("form") == "two-closures"
    lobe = "refraction" if two_closures else node
    entering = slice_read(chain, glass_image(glass, lobe, "entering"), cell, "E entering")
    if lobe == "refraction":
        leaving = slice_read(chain, glass_image(glass, lobe, "leaving"),
                             around_critical(chain, cell, table, mu, n), "E leaving")
    else:
        leaving = slice_read(chain, glass_image(glass, lobe, "leaving"), cell, "E leaving")
    albedo = chain.mix_value("E = the back face's (leaving) or the front's (entering)",
                             geometry.outputs["Backfacing"], entering, leaving)
    if two_closures:
        albedo = two_closure_albedo(tree, chain, glass, group_in, cell, n, albedo, frame)
    bsdf = nodes.new(kind)
    bsdf.name = label
    bsdf.distribution = spec["distribution"]
    links.new(group_in.outputs["Roughness"], bsdf.inputs["Roughness"])
    links.new(n, bsdf.inputs["IOR"])
    links.new(group_in.outputs["Normal"], bsdf.inputs["Normal"])
    physical = params.get("color_model") == "physical"
    if physical:
        averages = [slice_read(chain, glass_image(glass, node, side, "average"), cell,
                               "E_avg %s" % side)
                    for side in ("entering", "leaving")]
        e_avg = chain.mix_value("E_avg = the back face's (leaving) or the front's (entering)",
                                geometry.outputs["Backfacing"], averages[0], averages[1])
        color = physical_color(chain, group_in.outputs["Color"], albedo, e_avg)
        colored_bsdf(tree, color, bsdf, FRAME_INSET + COLUMN_STEP * (chain.column + 2))
    else:
        gain = chain.math("DIVIDE", "Gain = 1 / E", 1.0, albedo, name="Gain")
        gained_bsdf(tree, group_in, gain, bsdf, FRAME_INSET + COLUMN_STEP * (chain.column + 2))
    colour = (
        "Its colour is Color (1 + Fms (1 - E) / E) with Fms = C E_avg / (1 - C (1 - E_avg)) and "
        "E_avg(r, eta) the side's average: the light the microfacets bounce more than once is "
        "tinted by the colour, as in Blender's Multiscatter GGX glass." if physical else
        "Its colour is Color / E, so every interface returns Color of what meets it.")
    return description_text(spec, params, (
        "Blender's %s %s (%s) whose colour restores E(mu, r, eta), the albedo of one "
        "rough interface for the view's cosine at the normal it shades with (see '%s'), "
        "eta = IOR on a front face and 1 / IOR on a back face, read from the packed tables "
        "'%s ...'. Every interface returns all the light that meets it, entering and "
        "leaving, so a white solid glass object in an evenly lit white world is 100 %% "
        "bright. %s Cycles only."
        % (spec["distribution"], label, what, spec["normal_group"], glass["image"], colour)))
