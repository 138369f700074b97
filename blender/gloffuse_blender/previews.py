# ---------------------------------------------------------------------------
# gloffuse previews.py: the Asset Browser previews of the generate job. Every
# group with a BSDF output is rendered once, on a small sphere in a studio
# light (a sky bright above, dark below) with a small sun whose highlight shows
# the distribution's lobe, in the colour its kind is for (white for the
# corrections of a glossy surface, gold for multiscatter's tinted bounces,
# an orange base under the layered coat), captioned with its distribution and
# kind so that no two thumbnails look alike; the picture becomes the custom
# preview of that group and of the helper groups it uses. Everything made for
# the renders is removed afterwards: the saved file holds only the groups.
#
# A module of the gloffuse_blender package, used by the generate job
# (generate.py). Functions and constants only.
# ---------------------------------------------------------------------------
import math
import os

import bpy
from mathutils import Vector

from .compat import (
    compat_camera_rays_only,
    compat_disable_denoising,
    compat_disable_post_processing,
    compat_node_tree,
    compat_png_settings,
)
from .meshes import sphere_mesh
from .runtime import render_result_image

PREVIEW_SIZE = 128
PREVIEW_SAMPLES = 64
PREVIEW_ROUGHNESS = 0.35
# The colour each kind of group is shown in (the "Color" or "Base Color" input).
PREVIEW_COLORS = {
    "roughness": (0.8, 0.8, 0.8, 1.0),
    "view": (0.8, 0.8, 0.8, 1.0),
    "multiscatter": (1.0, 0.77, 0.34, 1.0),  # gold: its bounces take the colour
    "layered": (0.8, 0.3, 0.1, 1.0),  # an orange base under a clear coat
    "anisotropic": (0.72, 0.78, 0.9, 1.0),  # brushed steel
    "glass": (0.85, 0.95, 0.9, 1.0),  # a faint green, as window glass
    "refraction": (0.85, 0.95, 0.9, 1.0),
}
# The anisotropic group's preview stretches its highlight along the default tangent.
PREVIEW_ANISOTROPY = 0.8
SUN_TOWARDS = (-0.55, -0.75, 0.65)  # upper left, in front: the highlight sits off centre
SUN_STRENGTH = 3.0
SUN_ANGLE_DEGREES = 4.0
SPHERE_RADIUS = 0.8
SPHERE_HEIGHT = 0.3  # above the centre, leaving room for the caption below
CAPTION_SIZE = 0.26
CAPTION_TOP = -0.62


def _studio_world():
    world = bpy.data.worlds.new("gloffuse preview world")
    tree = compat_node_tree(world)
    tree.nodes.clear()
    coords = tree.nodes.new("ShaderNodeTexCoord")
    split = tree.nodes.new("ShaderNodeSeparateXYZ")
    tree.links.new(coords.outputs["Generated"], split.inputs[0])
    ramp = tree.nodes.new("ShaderNodeMapRange")
    ramp.inputs["From Min"].default_value = -1.0
    ramp.inputs["From Max"].default_value = 1.0
    ramp.inputs["To Min"].default_value = 0.03
    ramp.inputs["To Max"].default_value = 0.9
    tree.links.new(split.outputs["Z"], ramp.inputs["Value"])
    background = tree.nodes.new("ShaderNodeBackground")
    tree.links.new(ramp.outputs["Result"], background.inputs["Strength"])
    output = tree.nodes.new("ShaderNodeOutputWorld")
    tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    return world


def _preview_scene(made):
    scene = bpy.data.scenes.new("gloffuse previews")
    made.append(scene)
    render = scene.render
    render.engine = "CYCLES"
    render.resolution_x = render.resolution_y = PREVIEW_SIZE
    render.resolution_percentage = 100
    scene.cycles.samples = PREVIEW_SAMPLES
    scene.cycles.device = "CPU"
    compat_disable_denoising(scene)
    compat_disable_post_processing(render)
    compat_png_settings(render.image_settings)
    render.film_transparent = True  # the Asset Browser shows the sphere alone
    scene.world = _studio_world()
    made.append(scene.world)
    camera_data = bpy.data.cameras.new("gloffuse preview camera")
    camera_data.type = "ORTHO"
    camera_data.ortho_scale = 2.3
    camera = bpy.data.objects.new("gloffuse preview camera", camera_data)
    camera.location = (0.0, -5.0, 0.0)
    camera.rotation_euler = (math.radians(90.0), 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    made.extend([camera, camera_data])
    sun_data = bpy.data.lights.new("gloffuse preview sun", "SUN")
    sun_data.energy = SUN_STRENGTH
    sun_data.angle = math.radians(SUN_ANGLE_DEGREES)
    sun = bpy.data.objects.new("gloffuse preview sun", sun_data)
    sun.rotation_mode = "QUATERNION"
    # A sun shines along its -Z: its +Z points at where the light comes from.
    sun.rotation_quaternion = Vector(SUN_TOWARDS).to_track_quat("Z", "Y")
    scene.collection.objects.link(sun)
    made.extend([sun, sun_data])
    mesh = sphere_mesh("gloffuse preview sphere", SPHERE_RADIUS, 64, 32)
    sphere = bpy.data.objects.new("gloffuse preview sphere", mesh)
    sphere.location = (0.0, 0.0, SPHERE_HEIGHT)
    scene.collection.objects.link(sphere)
    made.extend([sphere, mesh])
    caption = _caption_object(made)
    scene.collection.objects.link(caption)
    return scene, mesh, caption.data


def _caption_object(made):
    """A centred text object facing the camera below the sphere, in a flat light
    grey seen by the camera only; its text is set per preview."""
    curve = bpy.data.curves.new("gloffuse preview caption", "FONT")
    curve.align_x = "CENTER"
    curve.align_y = "TOP"
    curve.size = CAPTION_SIZE
    caption = bpy.data.objects.new("gloffuse preview caption", curve)
    caption.location = (0.0, -1.5, CAPTION_TOP)
    caption.rotation_euler = (math.radians(90.0), 0.0, 0.0)
    material = bpy.data.materials.new("gloffuse preview caption")
    tree = compat_node_tree(material)
    tree.nodes.clear()
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (0.85, 0.85, 0.85, 1.0)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    curve.materials.append(material)
    compat_camera_rays_only(caption)
    made.extend([caption, curve, material])
    return caption


def preview_caption(spec, kind):
    """The two lines under a preview: the distribution, spelled as the group
    names spell it ("Gloffuse (Ashikhmin-Shirley)"), then the kind of group,
    after "EEVEE" for EEVEE's groups (the first line is as wide as fits)."""
    name = spec["shader_group"]
    distribution = name[name.rindex("(") + 1:name.rindex(")")]
    engine = "EEVEE " if spec.get("engine") == "eevee" else ""
    return "%s\n%s%s" % (distribution, engine, kind)


def _render_group(scene, mesh, tree, color, path, made):
    material = bpy.data.materials.new("gloffuse preview " + tree.name)
    made.append(material)
    node_tree = compat_node_tree(material)
    node_tree.nodes.clear()
    group = node_tree.nodes.new("ShaderNodeGroup")
    group.node_tree = tree
    color_input = "Color" if "Color" in group.inputs else "Base Color"  # layered groups
    group.inputs[color_input].default_value = color
    group.inputs["Roughness"].default_value = PREVIEW_ROUGHNESS
    if "Anisotropy" in group.inputs:
        group.inputs["Anisotropy"].default_value = PREVIEW_ANISOTROPY
    output = node_tree.nodes.new("ShaderNodeOutputMaterial")
    node_tree.links.new(group.outputs["BSDF"], output.inputs["Surface"])
    mesh.materials[0] = material
    with bpy.context.temp_override(scene=scene):
        bpy.ops.render.render(write_still=False)
        render_result_image().save_render(filepath=path)


def _set_preview(tree, path):
    with bpy.context.temp_override(id=tree):
        bpy.ops.ed.lib_id_load_custom_preview(filepath=path)


def preview_groups(spec):
    """The groups of `spec` that get a rendered preview, in order, each with its
    kind and the helper groups that share it: [(shader group name, kind,
    [helper names])]."""
    view = spec.get("view") or {}
    layered = spec.get("layered") or {}
    anisotropic = spec.get("anisotropic") or {}
    glass = spec.get("glass") or {}
    groups = [(spec["shader_group"], "roughness", [spec["correction_group"]]),
              (view.get("shader_group"), "view", [view.get("correction_group")]),
              (view.get("multiscatter_group"), "multiscatter", []),
              (layered.get("shader_group"), "layered", []),
              (anisotropic.get("shader_group"), "anisotropic", []),
              (glass.get("glass_group"), "glass", []),
              (glass.get("refraction_group"), "refraction", [])]
    return [(name, kind, helpers) for name, kind, helpers in groups if name]


def render_previews(built, directory, on_preview=None):
    """Render a preview for every group of `built` (groups.py's build_all) that
    preview_groups names, into `directory`, and set it as the custom preview of
    that group and of the groups without one that belong to it (the normal
    group gets the first view, multiscatter, layered or anisotropic group's).
    on_preview(tree name), if given, is told before each render. Headless
    only."""
    images_before = {image.name for image in bpy.data.images}
    fonts_before = {font.name for font in bpy.data.fonts}
    made = []
    scene, mesh, caption = _preview_scene(made)
    try:
        shown, normals, first_user = {}, {}, {}
        for spec, trees in built:
            by_name = {tree.name: tree for tree in trees}
            for shader_name, kind, helpers in preview_groups(spec):
                tree = by_name.get(shader_name)
                if tree is None:
                    continue
                if on_preview is not None:
                    on_preview(tree.name)
                path = os.path.join(directory, "preview %d.png" % len(shown))
                caption.body = preview_caption(spec, kind)
                _render_group(scene, mesh, tree, PREVIEW_COLORS[kind], path, made)
                _set_preview(tree, path)
                shown[tree.name] = path
                for helper in helpers:
                    if helper in by_name:
                        _set_preview(by_name[helper], path)
            normal_name = spec.get("normal_group")
            if normal_name in by_name:
                normals[normal_name] = by_name[normal_name]
            view = spec.get("view") or {}
            layered = spec.get("layered") or {}
            first_view = (view.get("shader_group") or view.get("multiscatter_group")
                          or layered.get("shader_group")
                          or (spec.get("anisotropic") or {}).get("shader_group")
                          or (spec.get("glass") or {}).get("glass_group"))
            if normal_name is not None and first_view in shown:
                first_user.setdefault(normal_name, shown[first_view])
        # A normal group is built with the first spec that uses it, but that spec may
        # have no per-pixel group of its own (an anisotropic library: only GGX has one).
        for name, tree in normals.items():
            if name in first_user:
                _set_preview(tree, first_user[name])
    finally:
        # One batch: removing a mesh one by one would take its object with it first.
        bpy.data.batch_remove(made)
        for image in list(bpy.data.images):
            if image.name not in images_before and image.type in ("RENDER_RESULT", "COMPOSITING"):
                bpy.data.images.remove(image)
        for font in list(bpy.data.fonts):
            if font.name not in fonts_before:  # the built-in font the captions loaded
                bpy.data.fonts.remove(font)
