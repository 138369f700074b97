# ---------------------------------------------------------------------------
# glass_interface.py: renders one rough dielectric interface at a time with
# Blender's own Glass or Refraction BSDF, for tests/glass_e2e.rs to compare
# with the integrator's E(mu, r, eta) ring by ring.
#
#     glass_interface.py CASES.json OUT.json
#
# CASES.json: {"px": N, "samples": S, "cases": [{"node": "glass" |
# "refraction", "distribution": "GGX" | "BECKMANN", "roughness": r, "ior": n,
# "inside": bool}, ...]}. A unit sphere (smooth UV sphere) at the origin, an
# orthographic camera on -Y looking along +Y with ortho scale 2 (pixel
# (col, row) sees x = (col + 1/2)/N * 2 - 1, z likewise, bottom row first), a
# white world of strength 1 and a point-like pixel filter. The first surface
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

NODES = {"glass": "ShaderNodeBsdfGlass", "refraction": "ShaderNodeBsdfRefraction"}


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
    bsdf = nodes.new(NODES[case["node"]])
    bsdf.distribution = case["distribution"]
    bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bsdf.inputs["Roughness"].default_value = case["roughness"]
    bsdf.inputs["IOR"].default_value = case["ior"]
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
