"""The .blend files of tests/audit_pipeline.rs: one material per entry of a JSON list.

    blender -b --factory-startup --python baseline_materials.py -- OUT.blend SPEC.json

Each entry is {"name": ..., "shader": "glossy" | "diffuse", "roughness": R, "ignore": TEXT
or null}: a single-scatter GGX Glossy BSDF of roughness R (white), or a white Diffuse
BSDF, into the Surface of the material's output; `ignore` becomes the material's
`gloffuse_ignore` custom property (a waiver).
"""
import json
import sys

import bpy


def build(entry):
    m = bpy.data.materials.new(entry["name"])
    m.use_nodes = True
    m.use_fake_user = True
    tree = m.node_tree
    for node in [n for n in tree.nodes if n.bl_idname != "ShaderNodeOutputMaterial"]:
        tree.nodes.remove(node)
    out = tree.nodes["Material Output"]
    if entry["shader"] == "glossy":
        node = tree.nodes.new("ShaderNodeBsdfGlossy")
        node.name = "Glossy"
        node.distribution = "GGX"
        node.inputs["Roughness"].default_value = entry["roughness"]
    else:
        node = tree.nodes.new("ShaderNodeBsdfDiffuse")
        node.name = "Diffuse"
    node.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    tree.links.new(node.outputs[0], out.inputs["Surface"])
    if entry.get("ignore") is not None:
        m["gloffuse_ignore"] = entry["ignore"]


def main():
    out, spec = sys.argv[-2:]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    with open(spec, encoding="utf-8") as f:
        for entry in json.load(f):
            build(entry)
    bpy.ops.wm.save_as_mainfile(filepath=out)


main()
