"""The PBR range rules' cases (tests/audit_pbr.rs), made inside real Blender independently
of gloffuse's package: it imports nothing of gloffuse_blender.

    blender -b --factory-startup -noaudio --python-exit-code 1 --python pbr_cases.py -- CASES.json OUT.blend
    python3 pbr_cases.py CASES.json OUT.blend   (bpy module)

CASES.json is a list of {"name", "node": "principled" | "diffuse" | "glossy", "color": [r, g, b]
linear, "metallic", "transmission", "via": "socket" | "rgb" | "texture"}; each case becomes a
material of that name whose surface is that node, with Multiscatter GGX wherever the node has
a distribution (so no energy rule but 3.x's principled-creates-energy fires).
"""
import json
import sys

import bpy


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    return argv[0], argv[1]


IDNAMES = {"principled": "ShaderNodeBsdfPrincipled", "diffuse": "ShaderNodeBsdfDiffuse",
           "glossy": "ShaderNodeBsdfGlossy"}


def material(case, mesh):
    m = bpy.data.materials.new(case["name"])
    m.use_nodes = True
    nodes, links = m.node_tree.nodes, m.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    node = nodes.new(IDNAMES[case["node"]])
    node.name = "Shader"
    if hasattr(node, "distribution"):
        node.distribution = "MULTI_GGX"
    color_input = node.inputs["Base Color" if case["node"] == "principled" else "Color"]
    color = list(case["color"]) + [1.0]
    if case["via"] == "rgb":
        rgb = nodes.new("ShaderNodeRGB")
        rgb.outputs[0].default_value = color
        color_input.default_value = (1.0, 1.0, 1.0, 1.0)
        links.new(rgb.outputs[0], color_input)
    elif case["via"] == "texture":
        links.new(nodes.new("ShaderNodeTexNoise").outputs["Color"], color_input)
    else:
        color_input.default_value = color
    if case["node"] == "principled":
        node.inputs["Metallic"].default_value = case.get("metallic", 0.0)
        for name in ("Transmission Weight", "Transmission"):  # 4.0+, 3.x
            if name in node.inputs:
                node.inputs[name].default_value = case.get("transmission", 0.0)
                break
    links.new(node.outputs[0], output.inputs["Surface"])
    mesh.materials.append(m)


def main():
    cases_path, out = args()
    with open(cases_path, encoding="utf-8") as f:
        cases = json.load(f)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.cycles.blur_glossy = 0.0
    mesh = bpy.data.meshes.new("Swatches")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    bpy.context.scene.collection.objects.link(bpy.data.objects.new("Swatches", mesh))
    for case in cases:
        material(case, mesh)
    bpy.ops.wm.save_as_mainfile(filepath=out)


main()
