# ---------------------------------------------------------------------------
# gloffuse layered_groups.py: "Gloffuse Layered (...)", a dielectric glossy
# coat over a diffuse base (spec["layered"]).
#
# The coat reflects A(mu, r, IOR): the albedo of the distribution's lobe with
# the exact dielectric Fresnel at each microfacet, plus the energy single
# scattering loses, tinted as Kulla and Conty (and Blender 4.x's Multiscatter
# GGX) do. The base is a Diffuse BSDF of colour Base Color x (1 - A). The coat:
# - GGX in Blender 4.0+: Principled BSDF's specular layer alone (Base Color
#   black), which applies the Fresnel at each microfacet as a real coat does,
#   so its lobe has the right shape under bump and directional light, not
#   only the right total (compat.principled_coat_node);
# - Beckmann in Blender 5.0+: a Metallic BSDF in Physical Conductor mode with
#   the coat's index and no extinction (5.0's exact conductor Fresnel is then
#   the dielectric one), single scattering, times the gain A / E_F from a
#   second packed table (compat.metallic_coat_node);
# - elsewhere, Blender's Glossy BSDF, which reflects E(mu, r) of white light,
#   with colour Specular Tint x A / E: the right total, a Fresnel-free shape.
# With a white base the surface reflects A + (1 - A) = 1: everything, at every
# roughness, view and index.
#
# A travels as one packed float image: slices side by side, slice k for the
# index whose z = F0^(1/4) is k z_max / (K - 1), each slice a grid over (r, mu)
# packed by cell as the E(mu, r) image is; the group reads the cell in the two
# slices around its IOR and mixes them linearly in z. The gain table is packed
# the same way. E comes from the view groups' E(mu, r) image, mu from the
# shading-normal group (normal_group.py).
#
# A module of the gloffuse_blender package; it uses view_groups.py's
# albedo_lookup, grid_cell, read_cell, bilinear and the two plus-diffuse
# builders. Functions and constants only.
# ---------------------------------------------------------------------------
from .compat import mark_asset, metallic_coat_node, principled_coat_node, set_tree_description
from .nodes import (
    COLUMN_STEP,
    FRAME_INSET,
    ROW_STEP,
    Chain,
    asset_fields,
    clamped_roughness,
    description_text,
    ensure_interface,
    new_frame,
    reuse_or_create_group,
)
from .normal_group import NORMAL_INPUT, bump_map_correction_inputs
from .params import finite_list
from .view_groups import (
    albedo_lookup,
    bilinear,
    corner_cells,
    glossy_plus_diffuse,
    shader_plus_diffuse,
    grid_cell,
    packed_float_image,
    read_cell,
    view_cosine,
)

# An index of 1 is no coat at all; the table's last slice (coat_table.ior_max) is the top.
LAYERED_IOR_MIN = 1.0


def layered_sockets(spec):
    """Base Color, Roughness, IOR, Specular Tint, Normal [, Bump Map Correction] -> BSDF."""
    return [
        {"in_out": "INPUT", "name": "Base Color", "type": "NodeSocketColor",
         "default": (0.8, 0.8, 0.8, 1.0), "description": "Colour of the diffuse base"},
        {"in_out": "INPUT", "name": "Roughness", "type": "NodeSocketFloat", "subtype": "FACTOR",
         "default": 0.5, "min": 0.0, "max": 1.0, "description": "Roughness of the coat (0..1)"},
        ior_input(spec["layered"]["coat_table"], "Index of refraction of the coat (1 = no coat)"),
        {"in_out": "INPUT", "name": "Specular Tint", "type": "NodeSocketColor",
         "default": (1.0, 1.0, 1.0, 1.0),
         "description": "Tint of the coat's reflection (the base still gets 1 - A)"},
        NORMAL_INPUT,
    ] + bump_map_correction_inputs(spec) + [
        {"in_out": "OUTPUT", "name": "BSDF", "type": "NodeSocketShader",
         "description": "Glossy coat plus diffuse base; a white base reflects everything"},
    ]


def slice_image(table, key, name, where):
    """The packed float image `name` of an index-sliced table's `key` (the coat
    table's "values": A, "gain": A / E_F; the glass table's four E) over
    (mu, r, IOR), slice by slice side by side: slice k packed by cell (see
    corner_cells in view_groups.py) fills columns k (size - 1) ..
    (k + 1) (size - 1) - 1, row i the cells between mu = i / (size - 1) and
    (i + 1) / (size - 1). `where` names the table in errors."""
    size, slices = int(table["size"]), int(table["slices"])
    values = finite_list(table.get(key), "%s.%s" % (where, key))
    if len(values) != size * slices * size:
        raise ValueError("%s.%s holds %d values, not %d x %d"
                         % (where, key, len(values), size * slices, size))
    cells = size - 1
    packed = [corner_cells(lambda i, j, k=k: values[(i * slices + k) * size + j], size, size)
              for k in range(slices)]
    pixels = []
    for i in range(cells):
        for slice_pixels in packed:
            pixels.extend(slice_pixels[4 * cells * i:4 * cells * (i + 1)])
    return packed_float_image(name, cells * slices, cells, pixels)


def ior_input(table, description):
    """The IOR input of a group reading an index-sliced table: 1.5 by
    default, from 1 to the table's last slice."""
    return {"in_out": "INPUT", "name": "IOR", "type": "NodeSocketFloat", "default": 1.5,
            "min": LAYERED_IOR_MIN, "max": float(table["ior_max"]), "description": description}


def clamped_ior(table, chain, ior):
    """n = IOR clamped to an index-sliced table's range."""
    ior_max = float(table["ior_max"])
    return chain.clamp("n = clamp(IOR, %g, %g)" % (LAYERED_IOR_MIN, ior_max), ior,
                       LAYERED_IOR_MIN, ior_max)


def slice_cell(table, chain, roughness, mu, n):
    """Nodes that find where (mu, r, n) falls in an index-sliced table: returns
    ((column in slice k, column in slice k + 1, row, across, up, t), rho), t
    the fraction of the way from slice k to k + 1 in z = F0^(1/4), and
    rho = (n - 1) / (n + 1) = sqrt(F0)."""
    size, slices = int(table["size"]), int(table["slices"])
    z_max = float(table["z_max"])
    # z = sqrt(|(n - 1) / (n + 1)|) = F0^(1/4).
    rho = chain.math("DIVIDE", "(n - 1) / (n + 1)", chain.math("SUBTRACT", "n - 1", n, 1.0),
                     chain.math("ADD", "n + 1", n, 1.0))
    z = chain.math("SQRT", "z = F0^(1/4)", chain.math("ABSOLUTE", "|(n - 1) / (n + 1)|", rho))
    # The slices are a grid over z / z_max in [0, 1], as r and mu are over theirs.
    k, t = grid_cell(chain, chain.math("MULTIPLY", "z / z_max", z, 1.0 / z_max), slices,
                     "z")  # view_groups.py
    column, across = grid_cell(chain, roughness, size, "r")
    row, up = grid_cell(chain, mu, size, "mu")
    # Slice k's cells start at column k (size - 1); slice k + 1's one slice on.
    first = chain.math("MULTIPLY_ADD", "column in slice k", k, size - 1.0, column)
    second = chain.math("ADD", "column in slice k + 1", first, size - 1.0)
    return (first, second, row, across, up, t), rho


def slice_read(chain, image, cell, what):
    """Nodes that read an index-sliced table `image` at `cell` (slice_cell): each
    slice bilinear in (r, mu), the two mixed linearly. Returns the socket."""
    first, second, row, across, up, t = cell
    v = [bilinear(chain, read_cell(chain, image, c, row, "%s(mu, r) slice %s" % (what, name)),
                  across, up, "%s slice %s" % (what, name))
         for c, name in ((first, "k"), (second, "k + 1"))]
    return chain.mix_value("%s = %s(k) + t (%s(k + 1) - %s(k))" % ((what,) * 4), t, v[0], v[1])


def after_chain(chain):
    """The x of the first column right of the chain's frame."""
    return FRAME_INSET + COLUMN_STEP * (chain.column + 2)


def principled_coat(tree, group_in, n, x):
    """The Principled coat (compat.principled_coat_node) with the group's
    Roughness, Specular Tint and Normal and index n, at x, or None before
    Blender 4.0. Returns its BSDF socket."""
    coat = principled_coat_node(tree.nodes)
    if coat is None:
        return None
    coat.name = "Coat: Principled BSDF"
    coat.label = "Coat: Principled BSDF, Base Color black (its specular layer)"
    coat.location = (x, 2 * ROW_STEP)
    for name in ("Roughness", "Specular Tint", "Normal"):
        tree.links.new(group_in.outputs[name], coat.inputs[name])
    tree.links.new(n, coat.inputs["IOR"])
    return coat.outputs[0]


def tinted_ior(chain, rho, tint):
    """Per channel, the index whose F0 is F0(n) x Specular Tint (Principled's
    tint of F0; grazing reflection stays white): (1 + s) / (1 - s) with
    s = rho x sqrt(tint), rho = (n - 1) / (n + 1) (slice_cell), the tint taken
    at least 0 (as Principled does) and s below 1. Vector Math's POWER exists
    where this coat is built (5.0+)."""
    root = chain.vector("POWER", "sqrt(tint)",
                        chain.vector("MAXIMUM", "max(tint, 0)", tint, (0.0, 0.0, 0.0)),
                        (0.5, 0.5, 0.5))
    s = chain.vector("MINIMUM", "s = min((n - 1) / (n + 1) sqrt(tint), 0.999)",
                     chain.vector("SCALE", "(n - 1) / (n + 1) sqrt(tint)", root, rho),
                     (0.999, 0.999, 0.999))
    return chain.vector("DIVIDE", "IOR per channel = (1 + s) / (1 - s)",
                        chain.vector("ADD", "1 + s", (1.0, 1.0, 1.0), s),
                        chain.vector("SUBTRACT", "1 - s", (1.0, 1.0, 1.0), s))


def metallic_coat(tree, chain, group_in, layered, cell, rho, distribution):
    """The Metallic coat (compat.metallic_coat_node) of `distribution`:
    single scattering with the dielectric Fresnel at each microfacet, times the
    gain A / E_F read from the coat gain table, as Metallic + (gain - 1) x
    Metallic (a Mix Shader's factor stops at 1, and the gain is below 2). Its
    IOR per channel tints F0 by Specular Tint. None before Blender 5.0, or
    when the spec has no gain table. Its nodes go right of the chain's.
    Returns its shader socket."""
    if not layered.get("coat_gain_image"):
        return None
    first = metallic_coat_node(tree.nodes, distribution)
    if first is None:
        return None
    gain_image = slice_image(layered["coat_table"], "gain", layered["coat_gain_image"],
                             "layered.coat_table")
    gain = slice_read(chain, gain_image, cell, "G")
    extra = chain.math("SUBTRACT", "gain - 1 = A / E_F - 1", gain, 1.0, name="Coat extra")
    ior = tinted_ior(chain, rho, group_in.outputs["Specular Tint"])
    second = metallic_coat_node(tree.nodes, distribution)
    nodes, links = tree.nodes, tree.links
    x = after_chain(chain)
    for node, y, name in ((first, 2 * ROW_STEP, "Coat: Metallic BSDF"),
                          (second, 4 * ROW_STEP, "Coat: Metallic BSDF (the extra)")):
        node.name = node.label = name
        node.location = (x, y)
        for socket in ("Roughness", "Normal"):
            links.new(group_in.outputs[socket], node.inputs[socket])
        links.new(ior, node.inputs["IOR"])
    mix = nodes.new("ShaderNodeMixShader")
    mix.name = mix.label = "(gain - 1) x Metallic"
    mix.location = (x + COLUMN_STEP, 3 * ROW_STEP)
    links.new(extra, mix.inputs["Fac"])
    links.new(second.outputs[0], mix.inputs[2])
    add = nodes.new("ShaderNodeAddShader")
    add.name = add.label = "Coat: gain x Metallic"
    add.location = (x + 2 * COLUMN_STEP, 2 * ROW_STEP)
    links.new(first.outputs[0], add.inputs[0])
    links.new(mix.outputs[0], add.inputs[1])
    return add.outputs[0]


def build_layered_group(spec, params):
    """Base Color, Roughness, IOR, Specular Tint, Normal -> BSDF: a coat
    reflecting A plus Diffuse(Base Color x (1 - A)); see the header for which
    coat."""
    layered = spec["layered"]
    tree = reuse_or_create_group(layered["shader_group"])
    ensure_interface(tree, layered_sockets(spec))
    group_in = tree.nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    frame = new_frame(tree, "Coat frame", "Coat albedo A(mu, r, IOR), mu at the shaded normal")
    r = clamped_roughness(tree, group_in, frame)
    mu = view_cosine(tree, spec, group_in, 1, frame)
    chain = Chain(tree, frame, column=2, y=0.0)
    coat_table = layered["coat_table"]
    n = clamped_ior(coat_table, chain, group_in.outputs["IOR"])
    cell, rho = slice_cell(coat_table, chain, r, mu, n)
    a = slice_read(chain, slice_image(coat_table, "values", layered["coat_image"],
                                      "layered.coat_table"),
                   cell, "A")
    base = chain.math("SUBTRACT", "1 - A", 1.0, a, name="Base weight")
    base_color = chain.vector("SCALE", "Base Color × (1 - A)", group_in.outputs["Base Color"],
                              base, name="Base colour")
    # The coat, the first that this Blender and distribution allow:
    # Principled's specular layer (GGX, 4.0+) or the Metallic BSDF (Beckmann,
    # 5.0+) carry the Fresnel at each microfacet, so the lobe has a real
    # coat's shape, not only its total (docs/PHYSICS.md §13); else a Glossy
    # scaled to reflect A.
    distribution = spec["distribution"]
    coat = None
    if distribution == "GGX":
        coat, kind = principled_coat(tree, group_in, n, after_chain(chain)), "principled"
    elif distribution == "BECKMANN":
        coat = metallic_coat(tree, chain, group_in, layered, cell, rho, distribution)
        kind = "metallic"
    if coat is not None:
        shader_plus_diffuse(tree, group_in, coat, base_color,  # view_groups.py
                            after_chain(chain) + 3 * COLUMN_STEP,
                            ("Base: Diffuse BSDF", "Coat + base"))
    else:
        kind = "glossy"
        albedo, _, column = albedo_lookup(tree, layered, r, mu, chain.column + 1, frame)
        chain.skip(column - chain.column)
        glossy_color = chain.vector("SCALE", "Specular Tint × A / E",
                                    group_in.outputs["Specular Tint"],
                                    chain.math("DIVIDE", "A / E", a, albedo, name="Coat weight"),
                                    name="Coat colour")
        glossy_plus_diffuse(tree, spec, group_in, glossy_color, base_color,  # view_groups.py
                            after_chain(chain),
                            ("Coat: Glossy BSDF (%s)" % distribution, "Base: Diffuse BSDF",
                             "Coat + base"))
    description = description_text(spec, params, (
        "%s, over a diffuse base of Base Color x (1 - A), with A(mu, r, IOR) read from the "
        "packed table '%s'. A white base reflects 100 %% at every roughness, view and IOR. "
        "mu is read at the normal the coat shades with (see '%s')."
        % (COAT_DESCRIPTIONS[kind] % distribution, layered["coat_image"], spec["normal_group"])))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", distribution, "layered"],
               asset_fields(params, "shader"))
    return tree


COAT_DESCRIPTIONS = {
    "principled": "A %s coat that is Principled BSDF's specular layer alone (Base Color black): "
                  "the exact Fresnel at each microfacet, Specular Tint as Principled's",
    "metallic": "A %s coat that is a Metallic BSDF (Physical Conductor, IOR the coat's, no "
                "extinction: the exact dielectric Fresnel at each microfacet) times the gain "
                "A / E_F, so it reflects A; Specular Tint tints F0 as Principled's",
    "glossy": "A Glossy %s coat scaled to reflect A(mu, r, IOR), the albedo of a dielectric "
              "microfacet coat with its lost energy given back (Kulla-Conty, as Multiscatter "
              "GGX)",
}
