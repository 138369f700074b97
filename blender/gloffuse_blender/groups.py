# ---------------------------------------------------------------------------
# gloffuse groups.py: build_all(params), the order in which every node group
# of the parameter document is built.
#
# A module of the gloffuse_blender package. Functions only.
#
#   group_names(params) -> every group name build_all builds
#   build_all(params) -> [(spec, [trees...]), ...]   (params resolved by
#                                                     params.py's resolve_params)
#   mark_library(params), library_contents() -> the marker of a gloffuse library
# ---------------------------------------------------------------------------
import bpy

from .anisotropic_groups import build_anisotropic_group
from .glass_groups import build_glass_group
from .layered_groups import build_layered_group
from .nodes import GLOFFUSE_CONTENT, GLOFFUSE_TAG, content_fingerprint, is_tagged
from .normal_group import build_normal_group
from .params import validate_params
from .roughness_groups import build_correction_group, build_shader_group
from .view_groups import build_multiscatter_group, build_view_correction_group, build_view_shader_group


def group_names(params):
    """Every node group name build_all(params) builds, in the order it builds them."""
    names = []
    for spec in params["groups"]:
        view = spec.get("view") or {}
        layered = spec.get("layered") or {}
        anisotropic = spec.get("anisotropic") or {}
        glass = spec.get("glass") or {}
        for name in (spec.get("normal_group") if view or layered or anisotropic or glass
                     else None,
                     spec["correction_group"], spec["shader_group"],
                     view.get("correction_group"), view.get("shader_group"),
                     view.get("multiscatter_group"), layered.get("shader_group"),
                     anisotropic.get("shader_group"), glass.get("glass_group"),
                     glass.get("refraction_group")):
            if name is not None and name not in names:
                names.append(name)
    return names


def build_all(params, on_spec=None):
    """Build (or rebuild in place) every group of the resolved parameters
    (params.py's resolve_params): for each spec the roughness-only pair, and
    with spec["view"] the view pair and/or the multiscatter group it names, and
    with spec["layered"] the layered group, with spec["anisotropic"] the
    anisotropic group, with spec["glass"] the glass and refraction groups,
    after the normal group they use
    (spec["normal_group"], shared by the specs of one engine). Returns
    [(spec, [trees...]), ...] in document order; a normal group comes first
    with the first spec that uses it. on_spec(spec), if given, is told before
    each spec is built."""
    validate_params(params)
    built = []
    normal_names = set()
    for spec in params["groups"]:
        if on_spec is not None:
            on_spec(spec)
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
        if spec.get("anisotropic"):
            trees.append(build_anisotropic_group(spec, params))
        if spec.get("glass"):
            trees.append(build_glass_group(spec, params, "glass"))
            trees.append(build_glass_group(spec, params, "refraction"))
        built.append((spec, trees))
    names = group_names(params)
    for _spec, trees in built:
        for tree in trees:
            if tree.name not in names:
                raise ValueError("group_names misses the group %r it must set aside" % tree.name)
            tree[GLOFFUSE_TAG] = params.get("gloffuse_version", "")
    # Fingerprinted once every tree is complete (a group's holds the groups it nests).
    for _spec, trees in built:
        for tree in trees:
            tree[GLOFFUSE_CONTENT] = content_fingerprint(tree)
    return built


def mark_library(params):
    """Mark the open file as a gloffuse library: its scenes carry the tag (the
    version). generate --blend replaces only a file that has it."""
    for scene in bpy.data.scenes:
        scene[GLOFFUSE_TAG] = params.get("gloffuse_version", "")


def library_contents():
    """None if the open file is a gloffuse library (a scene carries the tag),
    else what it holds instead, in words."""
    if any(is_tagged(scene) for scene in bpy.data.scenes):
        return None
    counts = [(len(bpy.data.objects), "object"), (len(bpy.data.materials), "material"),
              (len(bpy.data.meshes), "mesh"), (len(bpy.data.node_groups), "node group"),
              (len(bpy.data.images), "image")]
    held = ["%d %s%s" % (n, what, "" if n == 1 else "es" if what == "mesh" else "s")
            for n, what in counts if n]
    return "no gloffuse library marker; it holds %s" % (", ".join(held) or "nothing")
