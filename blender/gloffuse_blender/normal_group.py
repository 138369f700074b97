# ---------------------------------------------------------------------------
# gloffuse normal_group.py: the helper group every view-dependent group uses
# to find the normal a glossy BSDF really shades with, and its view cosine;
# one for Cycles' groups, one for EEVEE's (spec["normal_group"]).
#
# Cycles never hands a bump or normal-map normal straight to a glossy lobe: if
# the mirror reflection about N would dip below the true surface, it first
# raises N towards the geometric normal Ng (docs/PHYSICS.md §7). A view gain
# 1 / E(mu, r) must read mu from that raised normal. The group rebuilds, with
# Math nodes, the rule of the Blender it is built in (compat.py's
# valid_reflection_rule): 3.0-3.5's ensure_valid_reflection (two candidate
# roots, checked) or 3.6+'s ensure_valid_specular_reflection (one closed-form
# root), and from 4.1 it honours the material's Bump Map Correction through an
# input of the same name. EEVEE raises nothing: its group passes the normal
# on and clamps the view cosine to [0, 1], as EEVEE reads its table.
#
# A module of the gloffuse_blender package. Functions and constants only.
# ---------------------------------------------------------------------------
from .compat import (
    blender_version_string,
    has_bump_map_correction,
    mark_asset,
    set_parent,
    set_tree_description,
    valid_reflection_rule,
)
from .nodes import (
    COLUMN_STEP,
    FRAME_INSET,
    ROW_STEP,
    Chain,
    asset_fields,
    ensure_interface,
    new_frame,
    reuse_or_create_group,
    short_label,
)

NORMAL_INPUT = {
    "in_out": "INPUT", "name": "Normal", "type": "NodeSocketVector", "hide_value": True,
    "description": "Shading normal (bump or normal map); unconnected means the surface's own normal"}

BUMP_MAP_CORRECTION_INPUT = {
    "in_out": "INPUT", "name": "Bump Map Correction", "type": "NodeSocketFloat",
    "subtype": "FACTOR", "default": 1.0, "min": 0.0, "max": 1.0,
    "description": "1 as the material's Settings > Bump Map Correction is on (the default); "
                   "set 0 where it is off"}


def is_eevee(spec):
    """Are the spec's groups calibrated for EEVEE (which shades with a bump
    normal as it is) rather than Cycles (which raises it)?"""
    return spec.get("engine", "cycles") == "eevee"


def bump_map_correction_inputs(spec):
    """The Bump Map Correction input, for Cycles' groups in the Blenders that
    have the setting (it switches Cycles' raising of the normal off; EEVEE
    never raises it)."""
    return [BUMP_MAP_CORRECTION_INPUT] if has_bump_map_correction() and not is_eevee(spec) else []


def normal_group_sockets(spec):
    return [NORMAL_INPUT] + bump_map_correction_inputs(spec) + [
        {"in_out": "OUTPUT", "name": "Normal", "type": "NodeSocketVector",
         "description": "The normal %s glossy BSDF shades with"
                        % ("EEVEE's" if is_eevee(spec) else "Cycles'")},
        {"in_out": "OUTPUT", "name": "View Cosine", "type": "NodeSocketFloat",
         "description": "mu = N' · I, the view cosine at that normal"},
    ]


def _raised_normal_3_6(chain, I, Ng, X, Ix, Iz, t, a):
    """3.6+: the one root N'z² = (b ± √(b² − 4ac)) / 4a, + where Ix < 0."""
    b = chain.math("MULTIPLY", "b = 2 (a + Iz t)", chain.math("MULTIPLY_ADD", "a + Iz t", Iz, t, a), 2.0)
    s = chain.math("ADD", "t + Iz", t, Iz)
    c = chain.math("MULTIPLY", "c = (t + Iz)²", s, s)
    bb = chain.math("MULTIPLY", "b²", b, b)
    ac4 = chain.math("MULTIPLY", "4ac", chain.math("MULTIPLY", "ac", a, c), 4.0)
    # Math's Square Root is Cycles' safe_sqrtf: 0 below 0.
    root = chain.math("SQRT", "√(b² − 4ac)", chain.math("SUBTRACT", "b² − 4ac", bb, ac4))
    sign = chain.math("MULTIPLY_ADD", "±: +1 if Ix < 0",
                      chain.math("LESS_THAN", "Ix < 0", Ix, 0.0), 2.0, -1.0)
    top = chain.math("MULTIPLY_ADD", "b ± root", sign, root, b)
    nz2 = chain.math("DIVIDE", "N'z² = (b ± root) / 4a",
                     chain.math("MULTIPLY", "(b ± root) / 4", top, 0.25), a)
    nx = chain.math("SQRT", "N'x", chain.math("SUBTRACT", "1 − N'z²", 1.0, nz2))
    nz = chain.math("SQRT", "N'z", nz2)
    return chain.vector("ADD", "N' = N'x X + N'z Ng",
                        chain.vector("SCALE", "N'x X", X, nx),
                        chain.vector("SCALE", "N'z Ng", Ng, nz))


def _raised_normal_3_0(chain, I, Ng, X, Ix, Iz, t, a, minus_iz):
    """3.0-3.5: both roots N'z² = (c ± b) / 2a, each kept if it is in
    (1e-5, 1 + 1e-5]; of two, the one whose reflection is shallower while both
    are above 1e-5 (else the higher one); of none, Ng."""
    fac = chain.math("DIVIDE", "fac = 0.5 / a", 0.5, a)
    ix2 = chain.math("MULTIPLY", "Ix²", Ix, Ix)
    b = chain.math("SQRT", "b = √(Ix² (a − t²))",
                   chain.math("MULTIPLY", "Ix² (a − t²)", ix2,
                              chain.math("SUBTRACT", "a − t²", a, chain.math("MULTIPLY", "t²", t, t))))
    c = chain.math("MULTIPLY_ADD", "c = Iz t + a", Iz, t, a)
    roots = []
    for k, (op, text) in enumerate((("ADD", "c + b"), ("SUBTRACT", "c − b")), start=1):
        z2 = chain.math("MULTIPLY", "N%dz² = fac (%s)" % (k, text), chain.math(op, text, c, b), fac)
        above = chain.math("GREATER_THAN", "N%dz² > 1e-5" % k, z2, 1e-5)
        too_high = chain.math("GREATER_THAN", "N%dz² > 1 + 1e-5" % k, z2, 1.0 + 1e-5)
        valid = chain.math("MULTIPLY", "N%d valid" % k, above,
                           chain.math("SUBTRACT", "not N%dz² > 1 + 1e-5" % k, 1.0, too_high))
        x = chain.math("SQRT", "N%dx" % k, chain.math("SUBTRACT", "1 − N%dz²" % k, 1.0, z2))
        z = chain.math("SQRT", "N%dz" % k, z2)
        dot = chain.math("MULTIPLY_ADD", "N%d · I" % k, x, Ix, chain.math("MULTIPLY", "N%dz Iz" % k, z, Iz))
        height = chain.math("MULTIPLY_ADD", "R%d = 2 (N%d · I) N%dz − Iz" % (k, k, k),
                            chain.math("MULTIPLY", "(N%d · I) N%dz" % (k, k), dot, z), 2.0, minus_iz)
        roots.append((valid, x, z, height))
    (v1, x1, z1, r1), (v2, x2, z2, r2) = roots
    both_up = chain.math("MULTIPLY", "R1, R2 ≥ 1e-5",
                         chain.math("SUBTRACT", "R1 ≥ 1e-5", 1.0, chain.math("LESS_THAN", "R1 < 1e-5", r1, 1e-5)),
                         chain.math("SUBTRACT", "R2 ≥ 1e-5", 1.0, chain.math("LESS_THAN", "R2 < 1e-5", r2, 1e-5)))
    first_if_both = chain.mix_value("pick 1 of two", both_up,
                                    chain.math("GREATER_THAN", "R1 > R2", r1, r2),
                                    chain.math("LESS_THAN", "R1 < R2", r1, r2))
    both = chain.math("MULTIPLY", "both valid", v1, v2)
    first = chain.mix_value("pick 1", both, v1, first_if_both)
    nx = chain.mix_value("N'x", first, x2, x1)
    nz = chain.mix_value("N'z", first, z2, z1)
    raised = chain.vector("ADD", "N' = N'x X + N'z Ng",
                          chain.vector("SCALE", "N'x X", X, nx),
                          chain.vector("SCALE", "N'z Ng", Ng, nz))
    return chain.select("N' or Ng", chain.math("MAXIMUM", "any valid", v1, v2), Ng, raised)


def build_normal_group(spec, params):
    """The spec's normal group: Cycles' (the raised normal) or EEVEE's (the
    normal as given)."""
    if is_eevee(spec):
        return _build_eevee_normal_group(spec, params)
    return _build_cycles_normal_group(spec, params)


def _normal_frame(spec, label):
    """The normal group's tree, Group Input, frame, Geometry node and a Chain
    after it, with N = the Normal input normalised (unconnected, it arrives as
    (0, 0, 0): the surface's own normal)."""
    tree = reuse_or_create_group(spec["normal_group"])
    ensure_interface(tree, normal_group_sockets(spec))
    group_in = tree.nodes.new("NodeGroupInput")
    group_in.location = (0.0, 0.0)
    frame = new_frame(tree, "Normal frame", short_label(label))
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    geometry.name = "Geometry"
    set_parent(geometry, frame)
    geometry.location = (FRAME_INSET, -ROW_STEP)
    chain = Chain(tree, frame, column=1)
    given = group_in.outputs["Normal"]
    connected = chain.math("GREATER_THAN", "Normal connected", chain.vector("LENGTH", "|Normal|", given), 0.5)
    N = chain.select("N", connected, geometry.outputs["Normal"], chain.vector("NORMALIZE", "Normal / |Normal|", given))
    return tree, group_in, geometry, chain, N


def _finish_normal_group(tree, chain, params, used, mu, description):
    group_out = tree.nodes.new("NodeGroupOutput")
    group_out.location = (FRAME_INSET + COLUMN_STEP * (chain.column + 1) + 100.0, 0.0)
    tree.links.new(used, group_out.inputs["Normal"])
    tree.links.new(mu, group_out.inputs["View Cosine"])
    description += " Used by gloffuse's view-dependent groups. Generated by gloffuse %s in Blender %s." % (
        params.get("gloffuse_version", "?"), blender_version_string())
    set_tree_description(tree, description)
    mark_asset(tree, description, ["gloffuse", "normal"], asset_fields(params, "helper"))
    return tree


def _build_eevee_normal_group(spec, params):
    """Normal -> Normal, View Cosine: EEVEE shades a glossy lobe with the bump
    or normal-map normal as it is, and reads its split-sum table at N · I
    clamped to [0, 1] (measured: a strongly bumped sphere renders E(max(N · I,
    0)) pixel by pixel in 4.5 and 5.0, and in 3.4 wherever N · I >= 0)."""
    tree, group_in, geometry, chain, N = _normal_frame(
        spec, "EEVEE: N as given, mu = clamp(N · I, 0, 1)")
    mu = chain.clamp("View Cosine = clamp(N · I, 0, 1)",
                     chain.vector("DOT_PRODUCT", "N · I", N, geometry.outputs["Incoming"]), 0.0, 1.0)
    return _finish_normal_group(tree, chain, params, N, mu, (
        "The normal EEVEE's glossy BSDF shades with: a bump or normal-map normal as it is "
        "(or, unconnected, the surface's own), and the view cosine there, clamped to [0, 1] "
        "as EEVEE clamps it."))


def _build_cycles_normal_group(spec, params):
    """Normal [, Bump Map Correction] -> Normal, View Cosine: the normal
    Cycles' glossy BSDF shades with, and mu = N' · I."""
    rule = valid_reflection_rule()
    tree, group_in, geometry, chain, N = _normal_frame(
        spec, "N raised until its mirror reflection clears the surface (Cycles %s rule)" % rule)
    I, Ng = geometry.outputs["Incoming"], geometry.outputs["True Normal"]
    n_dot_ng = chain.vector("DOT_PRODUCT", "N · Ng", N, Ng)
    iz = chain.vector("DOT_PRODUCT", "Iz = I · Ng", I, Ng)
    minus_iz = chain.math("MULTIPLY", "−Iz", iz, -1.0)
    height = chain.math("MULTIPLY_ADD", "R · Ng = 2 (N · I)(N · Ng) − Iz",
                        chain.math("MULTIPLY", "(N · I)(N · Ng)", chain.vector("DOT_PRODUCT", "N · I", N, I), n_dot_ng),
                        2.0, minus_iz)
    t = chain.math("MINIMUM", "t = min(0.9 Iz, 0.01)", chain.math("MULTIPLY", "0.9 Iz", iz, 0.9), 0.01)
    needed = chain.math("LESS_THAN", "R · Ng < t", height, t)
    if has_bump_map_correction():
        needed = chain.math("MULTIPLY", "and Bump Map Correction", needed,
                            group_in.outputs["Bump Map Correction"])
    X = chain.vector("NORMALIZE", "X = N − (N · Ng) Ng, normalised",
                     chain.vector("SUBTRACT", "N − (N · Ng) Ng", N, chain.vector("SCALE", "(N · Ng) Ng", Ng, n_dot_ng)))
    ix = chain.vector("DOT_PRODUCT", "Ix = I · X", I, X)
    a = chain.math("MULTIPLY_ADD", "a = Ix² + Iz²", ix, ix, chain.math("MULTIPLY", "Iz²", iz, iz))
    if rule == "3.6":
        raised = _raised_normal_3_6(chain, I, Ng, X, ix, iz, t, a)
    else:
        raised = _raised_normal_3_0(chain, I, Ng, X, ix, iz, t, a, minus_iz)
    used = chain.select("Normal used", needed, N, raised)
    mu = chain.vector("DOT_PRODUCT", "View Cosine = N' · I", used, I)
    return _finish_normal_group(tree, chain, params, used, mu, (
        "The normal Cycles' glossy BSDF really shades with: a bump or normal-map normal "
        "(or, unconnected, the surface's own) raised towards the true normal wherever its "
        "mirror reflection would dip below the surface (Blender %s's rule%s), and the view "
        "cosine at it." % (rule, ", honouring Bump Map Correction" if has_bump_map_correction() else "")))


def normal_group_node(tree, normal_tree, group_in, location, frame=None):
    """A node of the normal group fed by the Group Input's Normal (and Bump Map
    Correction); returns it."""
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = normal_tree
    node.name = "Shading normal"
    node.label = short_label(normal_tree.name)
    node.width = 240.0
    if frame is not None:
        set_parent(node, frame)
    node.location = location
    for name in ("Normal", "Bump Map Correction"):
        if name in node.inputs:
            tree.links.new(group_in.outputs[name], node.inputs[name])
    return node
