# ---------------------------------------------------------------------------
# gloffuse groups.py: build_all(params), the order in which every node group
# of the parameter document is built.
#
# A module of the gloffuse_blender package. Functions only.
#
#   build_all(params) -> [(spec, [trees...]), ...]   (params resolved by
#                                                     params.py's resolve_params)
# ---------------------------------------------------------------------------
from .layered_groups import build_layered_group
from .normal_group import build_normal_group
from .params import validate_params
from .roughness_groups import build_correction_group, build_shader_group
from .view_groups import build_multiscatter_group, build_view_correction_group, build_view_shader_group


def build_all(params):
    """Build (or rebuild in place) every group of the resolved parameters
    (params.py's resolve_params): for each spec the roughness-only pair, and
    with spec["view"] the view pair and/or the multiscatter group it names, and
    with spec["layered"] the layered group, after the normal group they use
    (spec["normal_group"], shared by the specs of one engine). Returns
    [(spec, [trees...]), ...] in document order; a normal group comes first
    with the first spec that uses it."""
    validate_params(params)
    built = []
    normal_names = set()
    for spec in params["groups"]:
        correction = build_correction_group(spec, params)
        trees = [correction, build_shader_group(spec, params, correction)]
        normal = spec.get("normal_group")
        if normal is not None and normal not in normal_names:
            normal_names.add(normal)
            trees.insert(0, build_normal_group(spec, params))
        view = spec.get("view")
        if view:
            if view.get("correction_group"):
                view_correction = build_view_correction_group(spec, params)
                trees.append(view_correction)
                trees.append(build_view_shader_group(spec, params, view_correction))
            if view.get("multiscatter_group"):
                trees.append(build_multiscatter_group(spec, params))
        if spec.get("layered"):
            trees.append(build_layered_group(spec, params))
        built.append((spec, trees))
    return built
