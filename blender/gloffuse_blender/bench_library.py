# ---------------------------------------------------------------------------
# gloffuse bench_library.py: the main of the job that makes the benchmark's
# material library (`gloffuse bench --audit`).
#
# It saves a .blend of `count` materials numbered from `first`, a varied mix
# of what libraries hold (single-scatter and multiscatter glossy, Fresnel-mixed
# fake layering, Principled BSDF, a textured and bumped diffuse), so that the
# audit's time per material is measured on realistic node trees. Parameters:
# the document's "bench_library" section {"output", "count", "first"}.
#
#   python3 THIS.py (bpy) or blender -b --python THIS.py
# ---------------------------------------------------------------------------
import json

import bpy

from .compat import compat_node_tree, glossy_node
from .contract import check_fields
from .runtime import result_line, run_main, save_blend

# The kinds of material, in turn.
BENCH_KINDS = ("glossy-ggx", "glossy-beckmann", "mix-fresnel", "principled", "textured-diffuse",
               "multi-ggx-bump")


def bench_noise(nodes, links, scale):
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = scale
    coordinates = nodes.new("ShaderNodeTexCoord")
    links.new(coordinates.outputs["UV"], noise.inputs["Vector"])
    return noise


def bench_shader(kind, nodes, links, roughness):
    """The shader output socket of one material of `kind`."""
    if kind in ("glossy-ggx", "glossy-beckmann", "multi-ggx-bump"):
        distribution = {"glossy-ggx": "GGX", "glossy-beckmann": "BECKMANN"}.get(kind, "MULTI_GGX")
        glossy = glossy_node(nodes, distribution)
        glossy.inputs["Roughness"].default_value = roughness
        if kind == "multi-ggx-bump":
            bump = nodes.new("ShaderNodeBump")
            links.new(bench_noise(nodes, links, 8.0).outputs["Fac"], bump.inputs["Height"])
            links.new(bump.outputs["Normal"], glossy.inputs["Normal"])
        return glossy.outputs["BSDF"]
    if kind == "mix-fresnel":
        fresnel = nodes.new("ShaderNodeFresnel")
        diffuse = nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (0.8, 0.3, 0.1, 1.0)
        glossy = glossy_node(nodes, "GGX")
        glossy.inputs["Roughness"].default_value = roughness
        mix = nodes.new("ShaderNodeMixShader")
        links.new(fresnel.outputs["Fac"], mix.inputs["Fac"])
        links.new(diffuse.outputs["BSDF"], mix.inputs[1])
        links.new(glossy.outputs["BSDF"], mix.inputs[2])
        return mix.outputs["Shader"]
    if kind == "principled":
        principled = nodes.new("ShaderNodeBsdfPrincipled")
        principled.inputs["Roughness"].default_value = roughness
        return principled.outputs["BSDF"]
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    links.new(bench_noise(nodes, links, 5.0).outputs["Color"], diffuse.inputs["Color"])
    return diffuse.outputs["BSDF"]


def bench_library_main(document_text):
    section = check_fields(json.loads(document_text), "bench_library_document")["bench_library"]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    for index in range(section["first"], section["first"] + section["count"]):
        kind = BENCH_KINDS[index % len(BENCH_KINDS)]
        material = bpy.data.materials.new("bench %04d %s" % (index, kind))
        material.use_fake_user = True
        tree = compat_node_tree(material)
        tree.nodes.clear()
        output = tree.nodes.new("ShaderNodeOutputMaterial")
        roughness = 0.1 + 0.9 * ((index * 7) % 10) / 9.0
        shader = bench_shader(kind, tree.nodes, tree.links, roughness)
        tree.links.new(shader, output.inputs["Surface"])
    path = save_blend(section["output"])
    print(result_line("bench_library_result", {"output": path, "materials": section["count"]}))


def main(document_text):
    run_main(lambda: bench_library_main(document_text))
