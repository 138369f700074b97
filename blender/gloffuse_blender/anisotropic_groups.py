# ---------------------------------------------------------------------------
# gloffuse anisotropic_groups.py: the anisotropic group (spec["anisotropic"]:
# GGX, or Beckmann from 3.5): Blender's own anisotropic Glossy (3.x's
# Anisotropic BSDF, 4.x/5.x's Glossy with Anisotropy) whose colour is
# multiplied by 1 / E(mu, phi, ax, ay).
#
# What the lobe loses depends on where the view lies relative to the tangent,
# not only on mu. The group rebuilds what Cycles does with its inputs: the
# widths ax = a(1 - A), ay = a / (1 - A) (A < 0 swaps them; each clamped to 1,
# a = r^2), the tangent (unconnected: a Tangent node, radial about Z, as Cycles
# links one itself) turned about the normal by Rotation x 2 pi, the frame
# Y = normalize(N x T), X = Y x N at the normal the BSDF shades with (the
# normal group), and the view's azimuth phi from X, folded into [0, pi/2] by
# the lobe's mirror symmetries. E travels as a 4-D table (N.V, phi, sqrt(ax),
# sqrt(ay) on grid points) packed like the view groups' E(mu, r): each pixel
# holds the four corners of an (N.V, sqrt(ax)) cell, one block of cells per
# (phi, sqrt(ay)) grid point; four unfiltered reads and linear blends give the
# 4-linear interpolation, the same numbers in every engine.
#
# A module of the gloffuse_blender package. Functions and constants only.
#
#   build_anisotropic_group(spec, params) -> tree
# ---------------------------------------------------------------------------
import math

import bpy

from .compat import anisotropic_glossy_node, mark_asset, set_parent, set_tree_description
from .nodes import (
    COLUMN_STEP,
    FRAME_INSET,
    ROW_STEP,
    Chain,
    asset_fields,
    description_text,
    ensure_interface,
    gained_bsdf,
    new_frame,
    reuse_or_create_group,
)
from .normal_group import NORMAL_INPUT, bump_map_correction_inputs, normal_group_node
from .params import finite_list
from .view_groups import bilinear, grid_cell, packed_float_image, read_cell

ANISOTROPY_INPUTS = [
    {"in_out": "INPUT", "name": "Anisotropy", "type": "NodeSocketFloat", "subtype": "FACTOR",
     "default": 0.5, "min": -1.0, "max": 1.0,
     "description": "Stretch of the highlight along the tangent (> 0) or across it (< 0), "
                    "as the Glossy BSDF's Anisotropy"},
    {"in_out": "INPUT", "name": "Rotation", "type": "NodeSocketFloat", "subtype": "FACTOR",
     "default": 0.0, "min": 0.0, "max": 1.0,
     "description": "Turn of the tangent about the normal, in whole turns"},
]

TANGENT_INPUT = {
    "in_out": "INPUT", "name": "Tangent", "type": "NodeSocketVector", "hide_value": True,
    "description": "Tangent of the anisotropy; unconnected means radial about the object's Z "
                   "axis, as Blender's own default"}


def anisotropic_sockets(spec):
    """Color, Roughness, Anisotropy, Rotation, Normal, Tangent [, Bump Map
    Correction] -> BSDF."""
    color, roughness = (
        {"in_out": "INPUT", "name": "Color", "type": "NodeSocketColor",
         "default": (1.0, 1.0, 1.0, 1.0), "description": "Colour of the glossy reflection"},
        {"in_out": "INPUT", "name": "Roughness", "type": "NodeSocketFloat", "subtype": "FACTOR",
         "default": 0.5, "min": 0.0, "max": 1.0, "description": "Roughness (0..1)"})
    return [color, roughness] + ANISOTROPY_INPUTS + [NORMAL_INPUT, TANGENT_INPUT] \
        + bump_map_correction_inputs(spec) + [
            {"in_out": "OUTPUT", "name": "BSDF", "type": "NodeSocketShader",
             "description": "Anisotropic glossy BSDF at 100 % brightness for every view"}]


def anisotropic_image(anisotropic):
    """The packed float image holding E(mu, phi, ax, ay): pixel (l (n - 1) + j,
    k (n - 1) + i) holds the corners of the cell between mu_i and mu_i+1 and
    sqrt(ax)_j and sqrt(ax)_j+1, at azimuth phi_k and sqrt(ay)_l (bottom row
    first); table values[((k n + i) n + l) n + j] = E(mu_i, phi_k, rx_j, ry_l)."""
    table = anisotropic["table"]
    n, azimuths = int(table["size"]), int(table["azimuths"])
    values = finite_list(table["values"], "anisotropic.table.values")
    if len(values) != azimuths * n ** 3:
        raise ValueError("anisotropic.table holds %d values, not %d x %d^3"
                         % (len(values), azimuths, n))

    def at(k, i, l, j):
        return values[((k * n + i) * n + l) * n + j]

    pixels = []
    for k in range(azimuths):
        for i in range(n - 1):
            for l in range(n):
                for j in range(n - 1):
                    pixels.extend((at(k, i, l, j), at(k, i, l, j + 1),
                                   at(k, i + 1, l, j), at(k, i + 1, l, j + 1)))
    return packed_float_image(anisotropic["image"], (n - 1) * n, (n - 1) * azimuths, pixels)


def _tangent(tree, chain, group_in, normal, frame):
    """The tangent Cycles' lobe uses: the Tangent input (or, unconnected, a
    Tangent node radial about Z), turned about the shading normal by
    Rotation x 2 pi. Returns (tangent before the turn, turned tangent)."""
    nodes = tree.nodes
    default = nodes.new("ShaderNodeTangent")
    default.name = "Default tangent"
    default.label = "Tangent: radial about Z (Cycles' own default)"
    default.direction_type = "RADIAL"
    default.axis = "Z"
    set_parent(default, frame)
    default.location = (FRAME_INSET, -3 * ROW_STEP)
    given = group_in.outputs["Tangent"]
    connected = chain.math("GREATER_THAN", "Tangent connected",
                           chain.vector("LENGTH", "|Tangent|", given), 1e-6)
    tangent = chain.select("T", connected, default.outputs["Tangent"], given)
    turn = nodes.new("ShaderNodeVectorRotate")
    turn.name = "Turn the tangent"
    turn.label = "T turned about N by Rotation x 2 pi"
    turn.rotation_type = "AXIS_ANGLE"
    set_parent(turn, frame)
    turn.location = (FRAME_INSET + COLUMN_STEP * (chain.column + 1), chain.y)
    chain.skip(1)
    tree.links.new(tangent, turn.inputs["Vector"])
    tree.links.new(normal, turn.inputs["Axis"])
    tree.links.new(chain.math("MULTIPLY", "angle = Rotation x 2 pi",
                              group_in.outputs["Rotation"], 2.0 * math.pi),
                   turn.inputs["Angle"])
    return tangent, turn.outputs["Vector"]


def _widths(chain, group_in):
    """sqrt(ax), sqrt(ay) as Cycles maps Roughness r and Anisotropy A:
    a = r^2, A clamped to [-0.99, 0.99], s = (1 - |A|)^sign(A),
    ax = min(a s, 1), ay = min(a / s, 1)."""
    r = chain.clamp("r = clamp(Roughness)", group_in.outputs["Roughness"], 0.0, 1.0)
    alpha = chain.math("MULTIPLY", "a = r^2", r, r)
    a = chain.clamp("A = clamp(Anisotropy, -0.99, 0.99)", group_in.outputs["Anisotropy"], -0.99, 0.99)
    s = chain.math("POWER", "s = (1 - |A|)^sign(A)",
                   chain.math("SUBTRACT", "1 - |A|", 1.0, chain.math("ABSOLUTE", "|A|", a)),
                   chain.math("SIGN", "sign(A)", a))
    ax = chain.math("MINIMUM", "ax = min(a s, 1)", chain.math("MULTIPLY", "a s", alpha, s), 1.0)
    ay = chain.math("MINIMUM", "ay = min(a / s, 1)", chain.math("DIVIDE", "a / s", alpha, s), 1.0)
    return chain.math("SQRT", "sqrt(ax)", ax), chain.math("SQRT", "sqrt(ay)", ay)


def _azimuth(chain, normal, tangent, incoming):
    """phi / (pi/2): the view's azimuth from X in Cycles' frame Y =
    normalize(N x T), X = Y x N, folded into [0, 1]."""
    y = chain.vector("NORMALIZE", "Y = normalize(N x T)", chain.vector("CROSS_PRODUCT", "N x T", normal, tangent))
    x = chain.vector("CROSS_PRODUCT", "X = Y x N", y, normal)
    vx = chain.math("ABSOLUTE", "|I . X|", chain.vector("DOT_PRODUCT", "I . X", incoming, x))
    vy = chain.math("ABSOLUTE", "|I . Y|", chain.vector("DOT_PRODUCT", "I . Y", incoming, y))
    return chain.math("MULTIPLY", "t = phi / (pi/2)", chain.math("ARCTAN2", "phi = atan2(|I.Y|, |I.X|)", vy, vx),
                      2.0 / math.pi)


def _lookup(chain, anisotropic, mu, t, rx, ry):
    """E(mu, phi, ax, ay): four reads of the packed image and 4-linear
    interpolation."""
    table = anisotropic["table"]
    n, azimuths = float(table["size"]), float(table["azimuths"])
    image = anisotropic_image(anisotropic)
    row, up = grid_cell(chain, mu, int(n), "mu")
    column, across = grid_cell(chain, rx, int(n), "sqrt(ax)")
    k, along_phi = grid_cell(chain, t, int(azimuths), "phi")
    l, along_ry = grid_cell(chain, ry, int(n), "sqrt(ay)")
    values = {}
    for dk in (0, 1):
        block_row = chain.math("MULTIPLY_ADD", "row: (k + %d)(n - 1) + i" % dk,
                               chain.math("ADD", "k + %d" % dk, k, float(dk)), n - 1.0, row)
        for dl in (0, 1):
            block_column = chain.math("MULTIPLY_ADD", "column: (l + %d)(n - 1) + j" % dl,
                                      chain.math("ADD", "l + %d" % dl, l, float(dl)), n - 1.0, column)
            label = "E at phi_k+%d, sqrt(ay)_l+%d" % (dk, dl)
            values[dk, dl] = bilinear(chain, read_cell(chain, image, block_column, block_row, label),
                                      across, up, label)
    lower = chain.mix_value("E at phi_k", along_ry, values[0, 0], values[0, 1])
    upper = chain.mix_value("E at phi_k+1", along_ry, values[1, 0], values[1, 1])
    return chain.mix_value("E(mu, phi, ax, ay)", along_phi, lower, upper)


def build_anisotropic_group(spec, params):
    """Color, Roughness, Anisotropy, Rotation, Normal, Tangent -> BSDF: the
    anisotropic Glossy of colour Color / E(mu, phi, ax, ay)."""
    anisotropic = spec["anisotropic"]
    tree = reuse_or_create_group(anisotropic["shader_group"])
    ensure_interface(tree, anisotropic_sockets(spec))
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    frame = new_frame(tree, "Albedo frame", "Gain = 1 / E(mu, phi, ax, ay) at the shaded normal and tangent")
    shading = normal_group_node(tree, bpy.data.node_groups[spec["normal_group"]], group_in,
                                (FRAME_INSET, -ROW_STEP), frame)
    normal, mu = shading.outputs["Normal"], shading.outputs["View Cosine"]
    geometry = nodes.new("ShaderNodeNewGeometry")
    geometry.name = "Geometry"
    set_parent(geometry, frame)
    geometry.location = (FRAME_INSET, -2 * ROW_STEP)
    chain = Chain(tree, frame, column=1)
    tangent, turned = _tangent(tree, chain, group_in, normal, frame)
    rx, ry = _widths(chain, group_in)
    t = _azimuth(chain, normal, turned, geometry.outputs["Incoming"])
    albedo = _lookup(chain, anisotropic, mu, t, rx, ry)
    gain = chain.math("DIVIDE", "Gain = 1 / E", 1.0, albedo, name="Gain")
    glossy = anisotropic_glossy_node(nodes, spec["distribution"])
    glossy.name = "Anisotropic Glossy BSDF"
    for name in ("Roughness", "Anisotropy", "Rotation", "Normal"):
        links.new(group_in.outputs[name], glossy.inputs[name])
    links.new(tangent, glossy.inputs["Tangent"])
    x = FRAME_INSET + COLUMN_STEP * (chain.column + 1) + 150.0
    gained_bsdf(tree, group_in, gain, glossy, x)
    description = description_text(spec, params, (
        "Blender's anisotropic %s Glossy BSDF whose colour is multiplied by 1 / E(mu, phi, "
        "ax, ay): its albedo for the view's cosine and azimuth from the tangent at the "
        "normal it shades with (see '%s'), read from the packed table '%s', so every pixel "
        "of an evenly lit white surface is 100 %% whatever the anisotropy, rotation and "
        "tangent. Cycles only: EEVEE renders an anisotropic Glossy as an isotropic one."
        % (spec["distribution"], spec["normal_group"], anisotropic["image"])))
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", spec["distribution"], "anisotropic"],
               asset_fields(params, "shader"))
    return tree
