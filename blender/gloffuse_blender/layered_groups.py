# ---------------------------------------------------------------------------
# gloffuse layered_groups.py: "Gloffuse Layered (...)", a dielectric glossy
# coat over a diffuse base (spec["layered"]).
#
# The coat reflects A(mu, r, IOR): the albedo of the distribution's lobe with
# the exact dielectric Fresnel at each microfacet, plus the energy single
# scattering loses, tinted as Kulla and Conty (and Blender 4.x's Multiscatter
# GGX) do. Blender's Glossy BSDF reflects E(mu, r) of white light, so the coat
# is that Glossy with colour Specular Tint x A / E; the base is a Diffuse BSDF
# of colour Base Color x (1 - A). With a white base the surface reflects
# E (A / E) + (1 - A) = 1: everything, at every roughness, view and index.
#
# A travels as one packed float image: slices side by side, slice k for the
# index whose z = F0^(1/4) is k z_max / (K - 1), each slice a grid over (r, mu)
# packed by cell as the E(mu, r) image is; the group reads the cell in the two
# slices around its IOR and mixes them linearly in z. E comes from the view groups' E(mu, r) image, mu
# from the shading-normal group (normal_group.py).
#
# A module of the gloffuse_blender package; it uses view_groups.py's
# albedo_lookup, grid_cell, read_cell and bilinear. Functions and constants only.
# ---------------------------------------------------------------------------
from .compat import mark_asset, set_tree_description
from .nodes import (
    COLUMN_STEP,
    FRAME_INSET,
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
        {"in_out": "INPUT", "name": "IOR", "type": "NodeSocketFloat",
         "default": 1.5, "min": LAYERED_IOR_MIN,
         "max": float(spec["layered"]["coat_table"]["ior_max"]),
         "description": "Index of refraction of the coat (1 = no coat)"},
        {"in_out": "INPUT", "name": "Specular Tint", "type": "NodeSocketColor",
         "default": (1.0, 1.0, 1.0, 1.0),
         "description": "Tint of the coat's reflection (the base still gets 1 - A)"},
        NORMAL_INPUT,
    ] + bump_map_correction_inputs(spec) + [
        {"in_out": "OUTPUT", "name": "BSDF", "type": "NodeSocketShader",
         "description": "Glossy coat plus diffuse base; a white base reflects everything"},
    ]


def coat_image(layered):
    """The packed float image of A(mu, r, IOR), slice by slice side by side:
    slice k packed by cell (see corner_cells in view_groups.py) fills columns
    k (size - 1) .. (k + 1) (size - 1) - 1, row i the cells between
    mu = i / (size - 1) and (i + 1) / (size - 1)."""
    table = layered["coat_table"]
    size, slices = int(table["size"]), int(table["slices"])
    values = finite_list(table["values"], "layered.coat_table.values")
    if len(values) != size * slices * size:
        raise ValueError("layered.coat_table holds %d values, not %d x %d"
                         % (len(values), size * slices, size))
    cells = size - 1
    packed = [corner_cells(lambda i, j, k=k: values[(i * slices + k) * size + j], size, size)
              for k in range(slices)]
    pixels = []
    for i in range(cells):
        for slice_pixels in packed:
            pixels.extend(slice_pixels[4 * cells * i:4 * cells * (i + 1)])
    return packed_float_image(layered["coat_image"], cells * slices, cells, pixels)


def coat_lookup(layered, chain, roughness, mu, ior):
    """Nodes that read A(mu, r, IOR): the two slices around the index, each
    interpolated bilinearly in (r, mu), mixed linearly in z = F0^(1/4).
    Returns the A socket."""
    table = layered["coat_table"]
    size, slices = int(table["size"]), int(table["slices"])
    z_max = float(table["z_max"])
    # z = sqrt(|(n - 1) / (n + 1)|) = F0^(1/4), for n clamped to the table's range.
    ior_max = float(table["ior_max"])
    n = chain.clamp("n = clamp(IOR, %g, %g)" % (LAYERED_IOR_MIN, ior_max), ior,
                    LAYERED_IOR_MIN, ior_max)
    ratio = chain.math("DIVIDE", "(n - 1) / (n + 1)", chain.math("SUBTRACT", "n - 1", n, 1.0),
                       chain.math("ADD", "n + 1", n, 1.0))
    z = chain.math("SQRT", "z = F0^(1/4)", chain.math("ABSOLUTE", "|(n - 1) / (n + 1)|", ratio))
    # The slices are a grid over z / z_max in [0, 1], as r and mu are over theirs.
    k, t = grid_cell(chain, chain.math("MULTIPLY", "z / z_max", z, 1.0 / z_max), slices,
                     "z")  # view_groups.py
    column, across = grid_cell(chain, roughness, size, "r")
    row, up = grid_cell(chain, mu, size, "mu")
    image = coat_image(layered)
    # Slice k's cells start at column k (size - 1); slice k + 1's one slice on.
    first = chain.math("MULTIPLY_ADD", "column in slice k", k, size - 1.0, column)
    second = chain.math("ADD", "column in slice k + 1", first, size - 1.0)
    a = [bilinear(chain, read_cell(chain, image, c, row, "A(mu, r) slice " + name), across, up,
                  "A slice " + name)
         for c, name in ((first, "k"), (second, "k + 1"))]
    return chain.mix_value("A = A(k) + t (A(k + 1) - A(k))", t, a[0], a[1])


def build_layered_group(spec, params):
    """Base Color, Roughness, IOR, Specular Tint, Normal -> BSDF: Glossy(Specular
    Tint x A / E) + Diffuse(Base Color x (1 - A))."""
    layered = spec["layered"]
    tree = reuse_or_create_group(layered["shader_group"])
    ensure_interface(tree, layered_sockets(spec))
    nodes = tree.nodes
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    frame = new_frame(tree, "Coat frame",
                      "Coat albedo A(mu, r, IOR) and E(mu, r), mu at the shaded normal")
    r = clamped_roughness(tree, group_in, frame)
    mu = view_cosine(tree, spec, group_in, 1, frame)
    albedo, _, column = albedo_lookup(tree, layered, r, mu, 2, frame)
    chain = Chain(tree, frame, column=column, y=0.0)
    a = coat_lookup(layered, chain, r, mu, group_in.outputs["IOR"])
    weight = chain.math("DIVIDE", "A / E", a, albedo, name="Coat weight")
    glossy_color = chain.vector("SCALE", "Specular Tint × A / E", group_in.outputs["Specular Tint"],
                                weight, name="Coat colour")
    base = chain.math("SUBTRACT", "1 - A", 1.0, a, name="Base weight")
    base_color = chain.vector("SCALE", "Base Color × (1 - A)", group_in.outputs["Base Color"],
                              base, name="Base colour")
    glossy_plus_diffuse(tree, spec, group_in, glossy_color, base_color,  # view_groups.py
                        FRAME_INSET + COLUMN_STEP * (chain.column + 1),
                        ("Coat: Glossy BSDF (%s)" % spec["distribution"], "Base: Diffuse BSDF",
                         "Coat + base"))
    description = description_text(spec, params, (
        "Glossy %s coat over a diffuse base: the coat reflects A(mu, r, IOR), the albedo of "
        "a dielectric microfacet coat with its lost energy given back (Kulla-Conty, as "
        "Multiscatter GGX), read from the packed table '%s'; the base gets Base Color x "
        "(1 - A). A white base reflects 100 %% at every roughness, view and IOR. mu is read "
        "at the normal the glossy BSDF shades with (see '%s')."
        % (spec["distribution"], layered["coat_image"], spec["normal_group"])))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "layered"],
               asset_fields(params, "shader"))
    return tree
