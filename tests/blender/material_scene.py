# ---------------------------------------------------------------------------
# material_scene.py: the main of the tests' "real material" scene, bundled by
# tests/materials_e2e.rs with the gloffuse_blender modules it imports (so it
# builds the groups and the world exactly as gloffuse does).
#
# A white furnace (in the scene section's "engine", Cycles by default), but not a lab sphere: a perspective camera, an off-centre
# smooth sphere whose normal is tilted by a Noise texture (a procedural normal
# map) and whose roughness comes from a texture (r0 -> r1 across the object's x). Every
# variant of the document's "scene" section is rendered on that sphere, one
# render each, all with the same seed and a point-like pixel filter, so each
# pixel of every render is shaded at the same point with the same random
# numbers: the ratio of two renders is the ratio of their BSDF weights there.
#
# The scene section may also ask for a lit scene instead of the furnace
# ("lighting": "sky_sun": a sky graded from horizon to zenith plus a sun, as
# {"sky": [horizon, zenith], "sun": {"strength", "angle", "elevation",
# "azimuth"}}) and for a real Bump node instead of the tilted normal ("bump":
# {"strength", "distance"}), and for a "solid" sphere (true): seen by every
# kind of ray, so light refracted into it crosses its far side, with the
# furnace's bounces for solid glass (for the "glass" variants).
#
# Variants ("kind"):
#   glossy      a plain Glossy BSDF of "distribution" (MULTI_GGX included)
#   group       the shader group "group" (Color, Roughness, Normal inputs; any
#               other input set to a value from "inputs": {name: value})
#   correction  the correction group "group" feeding a plain Glossy of "distribution"
#   layered     the layered group "group" (Base Color = "color", Roughness,
#               "ior", "tint" as Specular Tint, Normal)
#   principled  a Principled BSDF with the same inputs ("distribution",
#               Multiscatter GGX by default)
#   glass       the glass group "group" (Color, Roughness, IOR "ior", Normal) or,
#               without "group", Blender's Glass BSDF of "distribution" with
#               the same inputs
#   metallic    a Metallic BSDF of "distribution" in Physical Conductor mode,
#               IOR "ior" on every channel, Extinction 0
#   probe       an emission of 0.5 + 0.5 v for v = the view direction ("incoming"),
#               the true normal, the tilted normal, or (r, 0, 0) ("roughness")
# Each render is written to output_dir/NAME.exr; one GLOFFUSE_RESULT line lists them.
# ---------------------------------------------------------------------------
import json
import math
import os
import sys

import bpy

from gloffuse_blender.compat import (
    blender_version_string,
    compat_camera_rays_only,
    compat_node_tree,
    compat_principled_dielectric,
)
from gloffuse_blender.furnace import furnace_render_settings, furnace_world, render_sweep
from gloffuse_blender.groups import build_all
from gloffuse_blender.meshes import sphere_mesh
from gloffuse_blender.params import resolve_params
from gloffuse_blender.runtime import run_main


def scene_section(document):
    scene = document.get("scene")
    if not isinstance(scene, dict) or not scene.get("variants"):
        raise ValueError("the document needs a 'scene' section with variants")
    return scene


def shading_inputs(tree, scene):
    """The roughness texture and the bumped normal every variant shares."""
    nodes, links = tree.nodes, tree.links
    coords = nodes.new("ShaderNodeTexCoord")
    split = nodes.new("ShaderNodeSeparateXYZ")
    links.new(coords.outputs["Object"], split.inputs[0])
    r0, r1 = scene["roughness"]
    ramp = nodes.new("ShaderNodeMapRange")
    ramp.inputs["From Min"].default_value = -1.0
    ramp.inputs["From Max"].default_value = 1.0
    ramp.inputs["To Min"].default_value = r0
    ramp.inputs["To Max"].default_value = r1
    ramp.clamp = True
    links.new(split.outputs["X"], ramp.inputs["Value"])
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = scene["noise_scale"]
    links.new(coords.outputs["Object"], noise.inputs["Vector"])
    bump_settings = scene.get("bump")
    if bump_settings:
        bump = nodes.new("ShaderNodeBump")
        bump.inputs["Strength"].default_value = bump_settings["strength"]
        bump.inputs["Distance"].default_value = bump_settings["distance"]
        links.new(noise.outputs["Fac"], bump.inputs["Height"])
        return ramp.outputs["Result"], bump.outputs["Normal"]
    # A procedural normal map: the smooth normal tilted by the noise colour
    # (2 c - 1, times "tilt"), so some normals lean far away from the viewer.
    # (Not a Bump node: Blender 3.0-3.5's Bump node raises its own output, and
    # 4.x's bumps are gentler, so neither would exercise the BSDF's raise.)
    signed = nodes.new("ShaderNodeVectorMath")
    signed.operation = "MULTIPLY_ADD"
    links.new(noise.outputs["Color"], signed.inputs[0])
    signed.inputs[1].default_value = (2.0 * scene["tilt"],) * 3
    signed.inputs[2].default_value = (-scene["tilt"],) * 3
    geometry = nodes.new("ShaderNodeNewGeometry")
    tilted = nodes.new("ShaderNodeVectorMath")
    tilted.operation = "ADD"
    links.new(geometry.outputs["Normal"], tilted.inputs[0])
    links.new(signed.outputs["Vector"], tilted.inputs[1])
    normal = nodes.new("ShaderNodeVectorMath")
    normal.operation = "NORMALIZE"
    links.new(tilted.outputs["Vector"], normal.inputs[0])
    return ramp.outputs["Result"], normal.outputs["Vector"]


def encoded(tree, vector):
    """0.5 + 0.5 v as a colour (emission stays non-negative)."""
    node = tree.nodes.new("ShaderNodeVectorMath")
    node.operation = "MULTIPLY_ADD"
    tree.links.new(vector, node.inputs[0])
    node.inputs[1].default_value = (0.5, 0.5, 0.5)
    node.inputs[2].default_value = (0.5, 0.5, 0.5)
    return node.outputs["Vector"]


def variant_material(scene, variant):
    material = bpy.data.materials.new("Scene %s" % variant["name"])
    tree = compat_node_tree(material)
    tree.nodes.clear()
    nodes, links = tree.nodes, tree.links
    output = nodes.new("ShaderNodeOutputMaterial")
    output.target = "ALL"
    roughness, normal = shading_inputs(tree, scene)
    color = tuple(variant.get("color", (1.0, 1.0, 1.0))) + (1.0,)
    kind = variant["kind"]
    if kind == "probe":
        geometry = nodes.new("ShaderNodeNewGeometry")
        probe = variant["probe"]
        if probe == "roughness":
            combine = nodes.new("ShaderNodeCombineXYZ")
            links.new(roughness, combine.inputs["X"])
            value = combine.outputs[0]
        else:
            value = {"incoming": geometry.outputs["Incoming"],
                     "true_normal": geometry.outputs["True Normal"],
                     "normal": normal}[probe]
        emission = nodes.new("ShaderNodeEmission")
        emission.inputs["Strength"].default_value = 1.0
        links.new(encoded(tree, value), emission.inputs["Color"])
        shader = emission.outputs[0]
    elif kind == "glossy":
        glossy = nodes.new("ShaderNodeBsdfGlossy")
        glossy.distribution = variant["distribution"]
        glossy.inputs["Color"].default_value = color
        links.new(roughness, glossy.inputs["Roughness"])
        links.new(normal, glossy.inputs["Normal"])
        shader = glossy.outputs[0]
    elif kind == "group":
        node = nodes.new("ShaderNodeGroup")
        node.node_tree = bpy.data.node_groups[variant["group"]]
        node.inputs["Color"].default_value = color
        for name, value in variant.get("inputs", {}).items():
            node.inputs[name].default_value = value
        links.new(roughness, node.inputs["Roughness"])
        links.new(normal, node.inputs["Normal"])
        shader = node.outputs["BSDF"]
    elif kind in ("layered", "principled"):
        if kind == "layered":
            node = nodes.new("ShaderNodeGroup")
            node.node_tree = bpy.data.node_groups[variant["group"]]
            node.inputs["IOR"].default_value = variant["ior"]
            shader = node.outputs["BSDF"]
        else:
            node = nodes.new("ShaderNodeBsdfPrincipled")
            node.distribution = variant.get("distribution", "MULTI_GGX")
            compat_principled_dielectric(node, variant["ior"])
            shader = node.outputs["BSDF"]
        node.inputs["Base Color"].default_value = color
        node.inputs["Specular Tint"].default_value = tuple(variant.get("tint", (1.0,) * 3)) + (1.0,)
        links.new(roughness, node.inputs["Roughness"])
        links.new(normal, node.inputs["Normal"])
    elif kind == "glass":
        if variant.get("group"):
            node = nodes.new("ShaderNodeGroup")
            node.node_tree = bpy.data.node_groups[variant["group"]]
        else:
            node = nodes.new("ShaderNodeBsdfGlass")
            node.distribution = variant["distribution"]
        node.inputs["Color"].default_value = color
        node.inputs["IOR"].default_value = variant["ior"]
        links.new(roughness, node.inputs["Roughness"])
        links.new(normal, node.inputs["Normal"])
        shader = node.outputs[0]
    elif kind == "metallic":
        node = nodes.new("ShaderNodeBsdfMetallic")
        node.distribution = variant["distribution"]
        node.fresnel_type = "PHYSICAL_CONDUCTOR"
        node.inputs["IOR"].default_value = (variant["ior"],) * 3
        node.inputs["Extinction"].default_value = (0.0, 0.0, 0.0)
        links.new(roughness, node.inputs["Roughness"])
        links.new(normal, node.inputs["Normal"])
        shader = node.outputs["BSDF"]
    elif kind == "correction":
        node = nodes.new("ShaderNodeGroup")
        node.node_tree = bpy.data.node_groups[variant["group"]]
        node.inputs["Color"].default_value = color
        links.new(roughness, node.inputs["Roughness"])
        links.new(normal, node.inputs["Normal"])
        glossy = nodes.new("ShaderNodeBsdfGlossy")
        glossy.distribution = variant["distribution"]
        links.new(node.outputs["Color"], glossy.inputs["Color"])
        links.new(roughness, glossy.inputs["Roughness"])
        links.new(normal, glossy.inputs["Normal"])
        shader = glossy.outputs[0]
    else:
        raise ValueError("variant %r: unknown kind %r" % (variant["name"], kind))
    links.new(shader, output.inputs["Surface"])
    return material


def sky_world(sky):
    """A sky graded linearly in the direction's height, from the horizon colour
    (and below) to the zenith colour."""
    world = bpy.data.worlds.new("Scene sky")
    tree = compat_node_tree(world)
    tree.nodes.clear()
    nodes, links = tree.nodes, tree.links
    coords = nodes.new("ShaderNodeTexCoord")
    split = nodes.new("ShaderNodeSeparateXYZ")
    links.new(coords.outputs["Generated"], split.inputs[0])
    height = nodes.new("ShaderNodeMath")
    height.operation = "MAXIMUM"
    links.new(split.outputs["Z"], height.inputs[0])
    height.inputs[1].default_value = 0.0
    horizon, zenith = (tuple(c) for c in sky)
    grade = nodes.new("ShaderNodeVectorMath")
    grade.operation = "MULTIPLY_ADD"
    links.new(height.outputs[0], grade.inputs[0])
    grade.inputs[1].default_value = tuple(z - h for z, h in zip(zenith, horizon))
    grade.inputs[2].default_value = horizon
    background = nodes.new("ShaderNodeBackground")
    links.new(grade.outputs["Vector"], background.inputs["Color"])
    background.inputs["Strength"].default_value = 1.0
    output = nodes.new("ShaderNodeOutputWorld")
    links.new(background.outputs["Background"], output.inputs["Surface"])
    return world


def add_sun(render_scene, sun):
    data = bpy.data.lights.new("Scene sun", "SUN")
    data.energy = sun["strength"]
    data.angle = math.radians(sun["angle"])
    light = bpy.data.objects.new("Scene sun", data)
    # A sun light shines down its local -Z: tilt it from the zenith, then turn it.
    light.rotation_euler = (math.radians(90.0 - sun["elevation"]), 0.0, math.radians(sun["azimuth"]))
    render_scene.collection.objects.link(light)


def build_scene(scene):
    render_scene = bpy.context.scene
    size = scene["resolution"]
    engine = scene.get("engine", "cycles")
    solid = bool(scene.get("solid"))
    settings = {"engine": engine, "cell": size, "samples": scene["samples"], "seed": scene["seed"],
                "threads": 0, "solid": solid}
    # The world first: some of EEVEE's settings are the world's.
    lit = scene.get("lighting", "furnace") == "sky_sun"
    render_scene.world = sky_world(scene["sky"]) if lit else furnace_world()
    furnace_render_settings(render_scene, settings, 1, 1)
    if lit:
        add_sun(render_scene, scene["sun"])
    # A point-like pixel filter: every sample of a pixel hits the same point.
    if engine == "cycles":
        render_scene.cycles.filter_width = 0.01
    else:
        render_scene.render.filter_size = 0.0

    data = bpy.data.cameras.new("Scene camera")
    data.lens = 50.0
    camera = bpy.data.objects.new("Scene camera", data)
    camera.location = (0.0, -5.0, 0.6)
    camera.rotation_euler = (math.radians(83.0), 0.0, 0.0)
    render_scene.collection.objects.link(camera)
    render_scene.camera = camera

    mesh = sphere_mesh("Scene sphere", 1.0, 96, 48)
    sphere = bpy.data.objects.new("Scene sphere", mesh)
    sphere.location = (0.45, 0.0, 0.25)
    render_scene.collection.objects.link(sphere)
    if not solid:
        compat_camera_rays_only(sphere)
    return render_scene, sphere


def scene_main(document_text):
    document = json.loads(document_text)
    scene = scene_section(document)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    build_all(resolve_params(document))
    render_scene, sphere = build_scene(scene)
    written = []
    for variant in scene["variants"]:
        sphere.data.materials[0] = variant_material(scene, variant)
        probe = variant["kind"] == "probe"
        if render_scene.render.engine == "CYCLES":
            render_scene.cycles.samples = scene["probe_samples"] if probe else scene["samples"]
        path = os.path.join(scene["output_dir"], variant["name"] + ".exr")
        render_sweep(path)
        written.append(path)
    # This test's own result, not one of the package's jobs (contract.py holds those).
    print("GLOFFUSE_RESULT " + json.dumps({
        "blender_version": blender_version_string(),
        "written": written,
    }, sort_keys=True))
    sys.stdout.flush()


def main(document_text):
    run_main(lambda: scene_main(document_text))
