# ---------------------------------------------------------------------------
# anisotropic_sphere.py: renders white furnace spheres with Blender's own
# anisotropic glossy BSDF, for tests/anisotropic_e2e.rs to compare with the
# integrator pixel by pixel.
#
#     anisotropic_sphere.py CASES.json OUT.json
#
# CASES.json: {"px": N, "samples": S, "script": optional gloffuse generate
# script, run first to build its groups in this Blender, "cases":
# [{"distribution": "GGX", "roughness": r, "anisotropy": a, "rotation": t,
# "group": optional name}, ...]}. A case with a "group" is shaded with that
# node group (white Color, the case's Roughness, Anisotropy and Rotation,
# Normal and Tangent unconnected); one without, with Blender's own BSDF. Each case is a unit sphere (smooth
# UV sphere) at the origin, an orthographic camera on -Y looking along +Y with
# ortho scale 2 (pixel (col, row) sees x = (col + 1/2)/N * 2 - 1, z likewise,
# bottom row first), a white world of strength 1, and a point-like pixel
# filter. The BSDF is 3.x's Anisotropic BSDF or 4.x/5.x's Glossy BSDF (its
# Anisotropy input) with the tangent of a Tangent node (radial about Z), as
# Cycles builds it when nothing is linked. OUT.json gets {"px": N, "renders":
# [[R of every pixel, bottom row first], ...]}.
# ---------------------------------------------------------------------------
import json
import math
import os
import sys
import tempfile

import bpy


def build_groups(script):
    """Run a gloffuse generate script in this process: its groups are built in
    the open file."""
    saved = sys.argv
    # No options; and the job is not the program (sys.argv[0] is this file, which
    # runpy would replace), so it returns instead of ending the process.
    sys.argv = [__file__]
    try:
        with open(script, encoding="utf-8") as handle:
            code = compile(handle.read(), script, "exec")
        exec(code, {"__name__": "__main__", "__file__": script})
    finally:
        sys.argv = saved


def group_material(case):
    name = case["group"]
    material = bpy.data.materials.new("group")
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    group = nodes.new("ShaderNodeGroup")
    group.node_tree = bpy.data.node_groups[name]
    group.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    for key, socket in (("roughness", "Roughness"), ("anisotropy", "Anisotropy"),
                        ("rotation", "Rotation")):
        group.inputs[socket].default_value = case.get(key, 0.0)
    links.new(group.outputs["BSDF"], output.inputs["Surface"])
    return material


def anisotropic_material(case):
    if case.get("group"):
        return group_material(case)
    material = bpy.data.materials.new("anisotropic")
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    kind = "ShaderNodeBsdfGlossy" if bpy.app.version >= (4, 0, 0) else "ShaderNodeBsdfAnisotropic"
    bsdf = nodes.new(kind)
    bsdf.distribution = case["distribution"]
    bsdf.inputs["Rotation"].default_value = case.get("rotation", 0.0)
    bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bsdf.inputs["Roughness"].default_value = case["roughness"]
    bsdf.inputs["Anisotropy"].default_value = case["anisotropy"]
    tangent = nodes.new("ShaderNodeTangent")
    tangent.direction_type = "RADIAL"
    tangent.axis = "Z"
    links.new(tangent.outputs["Tangent"], bsdf.inputs["Tangent"])
    links.new(bsdf.outputs[0], output.inputs["Surface"])
    return material


def build_scene(px, samples):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128, radius=1.0)
    sphere = bpy.context.object
    mesh = sphere.data
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 2.0
    camera.location = (0.0, -5.0, 0.0)
    camera.rotation_euler = (math.pi / 2, 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    world = bpy.data.worlds.new("white")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = 1.0
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.filter_width = 0.01
    scene.render.resolution_x = scene.render.resolution_y = px
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    return scene, sphere


def render_cases(argv, material_of, build=build_scene, prepare=None):
    """Render every case of the request argv[0] (see the header) on the scene
    `build(px, samples)` makes, each with `material_of(case)` (after
    `prepare(sphere, case)`, if given), and write {"px", "renders"} to argv[1]."""
    with open(argv[0], encoding="utf-8") as handle:
        request = json.load(handle)
    px = int(request["px"])
    scene, sphere = build(px, int(request["samples"]))
    if request.get("script"):
        build_groups(request["script"])
    renders = []
    with tempfile.TemporaryDirectory() as folder:
        for index, case in enumerate(request["cases"]):
            if prepare is not None:
                prepare(sphere, case)
            sphere.data.materials.clear()
            sphere.data.materials.append(material_of(case))
            scene.render.filepath = os.path.join(folder, "case%d.exr" % index)
            bpy.ops.render.render(write_still=True)
            image = bpy.data.images.load(scene.render.filepath)
            renders.append(list(image.pixels[:])[0::4])
            bpy.data.images.remove(image)
    with open(argv[1], "w", encoding="utf-8") as handle:
        json.dump({"px": px, "renders": renders}, handle)
    print("GLOFFUSE_RESULT rendered %d cases" % len(renders))


def main(argv):
    render_cases(argv, anisotropic_material)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
