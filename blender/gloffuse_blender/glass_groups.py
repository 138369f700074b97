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
# the critical angle) and the lobes' R and T from the tables; T falls as
# steeply there when leaving, so the glass reads it leaving from a table over
# u, the view cosine above the critical one (mu = mu_c + (1 - mu_c) u^2).
# mu comes from the shading-normal group (normal_group.py).
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
    gained_bsdf,
    new_frame,
    reuse_or_create_group,
)
from .normal_group import NORMAL_INPUT, bump_map_correction_inputs
from .view_groups import grid_cell, view_cosine

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


def glass_image(glass, node, side):
    """The packed float image of E for `node` ("glass" or "refraction") and
    `side` ("entering", "leaving", or for the two-closure glass's refraction
    lobe leaving "above_critical")."""
    key = "%s_%s" % (node, side)
    return slice_image(glass["table"], key, "%s %s %s" % (glass["image"], node, side),
                       "glass.table")


def above_critical(chain, cell, table, mu, n):
    """The cell of a two-closure table's refraction lobe above the critical
    angle (the glass's T leaving), whose rows are over
    u = sqrt((mu - mu_c) / (1 - mu_c)), mu_c = sqrt(1 - 1 / n^2) the cosine
    below which the back face reflects totally (gloffuse's above_critical):
    `cell` (slice_cell) with its row and fraction for u."""
    critical = chain.math("SQRT", "mu_c = sqrt(1 - 1/n^2)",
                          chain.math("SUBTRACT", "1 - 1/n^2", 1.0,
                                     chain.math("DIVIDE", "1/n^2", 1.0,
                                                chain.math("MULTIPLY", "n^2", n, n))))
    above = chain.math("DIVIDE", "(mu - mu_c) / (1 - mu_c)",
                       chain.math("SUBTRACT", "mu - mu_c", mu, critical),
                       chain.math("SUBTRACT", "1 - mu_c", 1.0, critical))
    u = chain.math("SQRT", "u = sqrt(clamp(...))", chain.clamp("clamp to [0, 1]", above, 0.0, 1.0))
    row, up = grid_cell(chain, u, int(table["size"]), "u")
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
    "refraction") of colour Color / E(mu, r, eta)."""
    glass = spec["glass"]
    kind, label, what = GLASS_NODES[node]
    tree = reuse_or_create_group(glass["%s_group" % node])
    ensure_interface(tree, glass_sockets(dict(glass, spec=spec)))
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
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
    cell, _ = slice_cell(table, chain, r, mu, n)
    two_closures = node == "glass" and table.get("form") == "two-closures"
    entering = slice_read(chain, glass_image(glass, "refraction" if two_closures else node,
                                             "entering"), cell, "E entering")
    if two_closures:
        leaving = slice_read(chain, glass_image(glass, "refraction", "above_critical"),
                             above_critical(chain, cell, table, mu, n), "E leaving")
    else:
        leaving = slice_read(chain, glass_image(glass, node, "leaving"), cell, "E leaving")
    albedo = chain.mix_value("E = the back face's (leaving) or the front's (entering)",
                             geometry.outputs["Backfacing"], entering, leaving)
    if two_closures:
        albedo = two_closure_albedo(tree, chain, glass, group_in, cell, n, albedo, frame)
    gain = chain.math("DIVIDE", "Gain = 1 / E", 1.0, albedo, name="Gain")
    bsdf = nodes.new(kind)
    bsdf.name = label
    bsdf.distribution = spec["distribution"]
    links.new(group_in.outputs["Roughness"], bsdf.inputs["Roughness"])
    links.new(n, bsdf.inputs["IOR"])
    links.new(group_in.outputs["Normal"], bsdf.inputs["Normal"])
    gained_bsdf(tree, group_in, gain, bsdf, FRAME_INSET + COLUMN_STEP * (chain.column + 2))
    description = description_text(spec, params, (
        "Blender's %s %s (%s) whose colour is divided by E(mu, r, eta), the albedo of one "
        "rough interface for the view's cosine at the normal it shades with (see '%s'), "
        "eta = IOR on a front face and 1 / IOR on a back face, read from the packed tables "
        "'%s ...'. Every interface returns all the light that meets it, entering and "
        "leaving, so a white solid glass object in an evenly lit white world is 100 %% "
        "bright. Cycles only."
        % (spec["distribution"], label, what, spec["normal_group"], glass["image"])))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "glass"],
               asset_fields(params, "shader"))
    return tree
