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
# strength 1, a point-like pixel filter and up to 1,024 bounces of every kind
# (Cycles' most; a solid glass sphere keeps light inside for many: at 64, a
# GGX r 0.1 sphere's rim renders 3.6 % dark). A "solid" case is that
# shader on every face. Otherwise the first surface
# a camera ray meets is the white BSDF; the second is a white Emission of
# strength 1 that scatters nothing and is not sampled as a light. So a pixel
# is what the interface returns of what reaches it: reflected light from the
# world and transmitted light from the Emission, each 1. With "inside" the
# sphere's normals point inwards: the camera meets a back face, which Cycles
# shades as the inside of the glass (index 1/n). OUT.json gets {"px": N,
# "renders": [[R of every pixel, bottom row first], ...]}.
# ---------------------------------------------------------------------------
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from anisotropic_sphere import build_scene as sphere_scene  # noqa: E402 (after the path it needs)
from anisotropic_sphere import render_cases  # noqa: E402

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
    """anisotropic_sphere.py's scene, with nothing blurred or clamped (the
    BSDF as it is) and 1,024 bounces of every kind."""
    scene, sphere = sphere_scene(px, samples)
    cycles = scene.cycles
    cycles.blur_glossy = 0.0
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    for kind in ("max", "diffuse", "glossy", "transmission", "transparent_max"):
        setattr(cycles, kind + "_bounces", 1024)
    return scene, sphere


def set_inside(sphere, inside):
    """Normals inwards for an "inside" case (flipped back after)."""
    if sphere.get("inside", False) != inside:
        sphere.data.flip_normals()
        sphere["inside"] = inside


def main(argv):
    render_cases(argv, interface_material, build=build_scene,
                 prepare=lambda sphere, case: set_inside(sphere, bool(case.get("inside"))))


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
