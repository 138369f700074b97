# ---------------------------------------------------------------------------
# gloffuse groups.py: build_all(params), the order in which every node group
# of the parameter document is built.
#
# One part of the script the gloffuse binary concatenates: header, compat.py,
# params.py, nodes.py, roughness_groups.py, view_groups.py, groups.py,
# runtime.py, then a main. Functions only.
#
#   build_all(params) -> [(spec, [trees...]), ...]
# ---------------------------------------------------------------------------

def build_all(params):
    """Build (or rebuild in place) every group in params["groups"]: for each
    spec the roughness-only pair, and with spec["view"] also the view pair and
    the multiscatter group. Returns [(spec, [trees...]), ...] in document order."""
    validate_params(params)
    built = []
    for spec in params["groups"]:
        correction = build_correction_group(spec, params)
        trees = [correction, build_shader_group(spec, params, correction)]
        if spec.get("view"):
            view_correction = build_view_correction_group(spec, params)
            trees.append(view_correction)
            trees.append(build_view_shader_group(spec, params, view_correction))
            trees.append(build_multiscatter_group(spec, params))
        built.append((spec, trees))
    return built
