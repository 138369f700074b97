# ---------------------------------------------------------------------------
# gloffuse previews.py: the Asset Browser previews of the generate job. Every
# group with a BSDF output is rendered once, on a small sphere in a studio
# light (a sky bright above, dark below), and the picture becomes the custom
# preview of that group and of the helper groups it uses. Everything made for
# the renders is removed afterwards: the saved file holds only the groups.
#
# A module of the gloffuse_blender package, used by the generate job
# (generate.py). Functions and constants only.
# ---------------------------------------------------------------------------
import math
import os

import bpy

from .compat import (
    compat_disable_denoising,
    compat_disable_post_processing,
    compat_node_tree,
    compat_png_settings,
)
from .meshes import sphere_mesh
from .runtime import render_result_image

PREVIEW_SIZE = 128
PREVIEW_SAMPLES = 64
PREVIEW_COLOR = (0.8, 0.8, 0.8, 1.0)
PREVIEW_ROUGHNESS = 0.35


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
    ramp.inputs["To Min"].default_value = 0.05
    ramp.inputs["To Max"].default_value = 1.5
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
    mesh = sphere_mesh("gloffuse preview sphere", 1.0, 64, 32)
    sphere = bpy.data.objects.new("gloffuse preview sphere", mesh)
    scene.collection.objects.link(sphere)
    made.extend([sphere, mesh])
    return scene, mesh


def _render_group(scene, mesh, tree, path, made):
    material = bpy.data.materials.new("gloffuse preview " + tree.name)
    made.append(material)
    node_tree = compat_node_tree(material)
    node_tree.nodes.clear()
    group = node_tree.nodes.new("ShaderNodeGroup")
    group.node_tree = tree
    color_input = "Color" if "Color" in group.inputs else "Base Color"  # layered groups
    group.inputs[color_input].default_value = PREVIEW_COLOR
    group.inputs["Roughness"].default_value = PREVIEW_ROUGHNESS
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
    """The groups of `spec` that get a rendered preview, in order, each with the
    helper groups that share it: [(shader group name, [helper names])]."""
    view = spec.get("view") or {}
    layered = spec.get("layered") or {}
    pairs = [(spec["shader_group"], [spec["correction_group"]]),
             (view.get("shader_group"), [view.get("correction_group")]),
             (view.get("multiscatter_group"), []),
             (layered.get("shader_group"), [])]
    return [(name, helpers) for name, helpers in pairs if name]


def render_previews(built, directory, on_preview=None):
    """Render a preview for every group of `built` (groups.py's build_all) that
    preview_groups names, into `directory`, and set it as the custom preview of
    that group and of the groups without one that belong to it (the normal
    group gets the first view group's). on_preview(tree name), if given, is
    told before each render. Headless only."""
    images_before = {image.name for image in bpy.data.images}
    made = []
    scene, mesh = _preview_scene(made)
    try:
        shown = {}
        for spec, trees in built:
            by_name = {tree.name: tree for tree in trees}
            for shader_name, helpers in preview_groups(spec):
                tree = by_name.get(shader_name)
                if tree is None:
                    continue
                if on_preview is not None:
                    on_preview(tree.name)
                path = os.path.join(directory, "preview %d.png" % len(shown))
                _render_group(scene, mesh, tree, path, made)
                _set_preview(tree, path)
                shown[tree.name] = path
                for helper in helpers:
                    if helper in by_name:
                        _set_preview(by_name[helper], path)
            view = spec.get("view") or {}
            layered = spec.get("layered") or {}
            normal = by_name.get(spec.get("normal_group"))
            first_view = view.get("shader_group") or layered.get("shader_group")
            if normal is not None and first_view in shown:
                _set_preview(normal, shown[first_view])
    finally:
        # One batch: removing a mesh one by one would take its object with it first.
        bpy.data.batch_remove(made)
        for image in list(bpy.data.images):
            if image.name not in images_before and image.type in ("RENDER_RESULT", "COMPOSITING"):
                bpy.data.images.remove(image)
