# ---------------------------------------------------------------------------
# glass_interface.py: renders rough dielectric spheres with Blender's own
# Glass or Refraction BSDF or a gloffuse glass group, for tests/glass_e2e.rs:
# one interface at a time (to compare with the integrator's E(mu, r, eta)
# ring by ring) or a solid sphere in the furnace.
#
#     glass_interface.py CASES.json OUT.json
#
# CASES.json: {"px": N, "samples": S, "script": optional gloffuse generate
# script, run first to build its groups in this Blender, "cases": [{"node":
# "glass" | "refraction", "distribution": "GGX" | "BECKMANN" | "MULTI_GGX",
# "roughness": r, "ior": n, "inside": bool, "solid": bool, "bump": bool,
# "group": optional name}, ...]}. A "bump" case takes its normal from Noise
# (scale 4) > Bump (strength 1, distance 0.3). A case with a "group" is shaded with that node group (white
# Color, the case's Roughness and IOR); one without, with Blender's own node.
# Every case: a unit sphere (smooth UV sphere) at the origin, an orthographic
# camera on -Y looking along +Y with ortho scale 2 (pixel (col, row) sees
# x = (col + 1/2)/N * 2 - 1, z likewise, bottom row first), a white world of
# strength 1, a point-like pixel filter and up to 64 bounces of every kind (a
# solid glass sphere keeps light inside for many). A "solid" case is that
# shader on every face. Otherwise the first surface
# a camera ray meets is the white BSDF; the second is a white Emission of
# strength 1 that scatters nothing and is not sampled as a light. So a pixel
# is what the interface returns of what reaches it: reflected light from the
# world and transmitted light from the Emission, each 1. With "inside" the
# sphere's normals point inwards: the camera meets a back face, which Cycles
# shades as the inside of the glass (index 1/n). OUT.json gets {"px": N,
# "renders": [[R of every pixel, bottom row first], ...]}.
# ---------------------------------------------------------------------------
import json
import math
import os
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from anisotropic_sphere import build_groups  # noqa: E402 (after the path it needs)

NODES = {"glass": "ShaderNodeBsdfGlass", "refraction": "ShaderNodeBsdfRefraction"}


def shader_node(nodes, case):
    """The case's BSDF node or group node, white, at its roughness and index."""
    if case.get("group"):
        node = nodes.new("ShaderNodeGroup")
        node.node_tree = bpy.data.node_groups[case["group"]]
    else:
        node = nodes.new(NODES[case["node"]])
        node.distribution = case["distribution"]
    node.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    node.inputs["Roughness"].default_value = case["roughness"]
    node.inputs["IOR"].default_value = case["ior"]
    if case.get("bump"):
        links = node.id_data.links
        noise = nodes.new("ShaderNodeTexNoise")
        noise.inputs["Scale"].default_value = 4.0
        bump = nodes.new("ShaderNodeBump")
        bump.inputs["Strength"].default_value = 1.0
        bump.inputs["Distance"].default_value = 0.3
        links.new(noise.outputs["Fac"], bump.inputs["Height"])
        links.new(bump.outputs["Normal"], node.inputs["Normal"])
    return node


def interface_material(case):
    material = bpy.data.materials.new("interface")
    material.use_nodes = True
    if hasattr(material.cycles, "emission_sampling"):
        material.cycles.emission_sampling = "NONE"
    else:
        material.cycles.sample_as_light = False
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    bsdf = shader_node(nodes, case)
    if case.get("solid"):
        links.new(bsdf.outputs[0], output.inputs["Surface"])
        return material
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    emission.inputs["Strength"].default_value = 1.0
    geometry = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    # Fac 0 (a front face) takes the first shader, 1 (a back face) the second.
    first, second = (emission, bsdf) if case.get("inside") else (bsdf, emission)
    links.new(first.outputs[0], mix.inputs[1])
    links.new(second.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], output.inputs["Surface"])
    return material


def build_scene(px, samples):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128, radius=1.0)
    sphere = bpy.context.object
    for polygon in sphere.data.polygons:
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
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.use_denoising = False
    cycles.filter_width = 0.01
    # Nothing blurred or clamped: the BSDF as it is.
    cycles.blur_glossy = 0.0
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    for kind in ("max", "diffuse", "glossy", "transmission", "transparent_max"):
        setattr(cycles, kind + "_bounces", 64)
    scene.render.resolution_x = scene.render.resolution_y = px
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    return scene, sphere


def set_inside(sphere, inside):
    """Normals inwards for an "inside" case (flipped back after)."""
    if sphere.get("inside", False) != inside:
        sphere.data.flip_normals()
        sphere["inside"] = inside


def main(argv):
    with open(argv[0], encoding="utf-8") as handle:
        request = json.load(handle)
    px = int(request["px"])
    scene, sphere = build_scene(px, int(request["samples"]))
    if request.get("script"):
        build_groups(request["script"])
    renders = []
    with tempfile.TemporaryDirectory() as folder:
        for index, case in enumerate(request["cases"]):
            set_inside(sphere, bool(case.get("inside")))
            sphere.data.materials.clear()
            sphere.data.materials.append(interface_material(case))
            scene.render.filepath = os.path.join(folder, "case%d.exr" % index)
            bpy.ops.render.render(write_still=True)
            image = bpy.data.images.load(scene.render.filepath)
            renders.append(list(image.pixels[:])[0::4])
            bpy.data.images.remove(image)
    with open(argv[1], "w", encoding="utf-8") as handle:
        json.dump({"px": px, "renders": renders}, handle)
    print("GLOFFUSE_RESULT rendered %d interfaces" % len(renders))


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
