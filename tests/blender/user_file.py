"""A user's own .blend for tests/library_file.rs and tests/user_blend.rs, made and inspected inside
real Blender, independently of gloffuse's package.

    blender -b --factory-startup -noaudio --python-exit-code 1 --python user_file.py -- \
        --make OUT.blend [--group NAME] [--texture] [--compress] [--glossy]
    blender ... --python user_file.py -- --inspect IN.blend --out RESULT.json
    python3 user_file.py ...   (bpy module)

--make saves a scene as an artist has it: a cube with the material
"Chair Paint"; with --group, that material uses the user's own local node
group NAME (a Value node "user value" = 0.123 wired to its output); with
--texture, an Image Texture node whose image "tex" has the relative path
//tex.png; with --compress, the file is saved compressed; with --glossy, its
surface is a single-scatter GGX Glossy BSDF at roughness 1 (which an audit's
fix replaces).
--inspect writes what the file holds: the Blender version that saved it,
every local node group (its gloffuse tag, its node names), every material
with the groups its nodes use, every image's file path, the scenes' gloffuse
tags, the number of objects, and the distribution of every BSDF node with
one, by material.
"""
import argparse
import json
import sys
import traceback

import bpy


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--make")
    parser.add_argument("--group")
    parser.add_argument("--texture", action="store_true")
    parser.add_argument("--compress", action="store_true")
    parser.add_argument("--glossy", action="store_true")
    parser.add_argument("--inspect")
    parser.add_argument("--out")
    return parser.parse_args(argv)


def user_group(name):
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    if hasattr(tree, "interface"):
        tree.interface.new_socket("Value", in_out="OUTPUT", socket_type="NodeSocketFloat")
    else:
        tree.outputs.new("NodeSocketFloat", "Value")
    value = tree.nodes.new("ShaderNodeValue")
    value.name = "user value"
    value.outputs[0].default_value = 0.123
    output = tree.nodes.new("NodeGroupOutput")
    tree.links.new(value.outputs[0], output.inputs[0])
    return tree


def rough_glossy(material):
    """A single-scatter GGX Glossy BSDF at roughness 1 as the surface: it loses
    energy in every Blender, so an audit's fix replaces it."""
    tree = material.node_tree
    glossy = tree.nodes.new("ShaderNodeBsdfGlossy")
    glossy.name = "rough glossy"
    glossy.distribution = "GGX"
    glossy.inputs["Roughness"].default_value = 1.0
    output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(glossy.outputs[0], output.inputs["Surface"])


def make(path, group, texture, compress, glossy):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    mesh = bpy.data.meshes.new("Cube")
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh.from_pydata(corners, [], faces)
    cube = bpy.data.objects.new("Cube", mesh)
    bpy.context.scene.collection.objects.link(cube)
    material = bpy.data.materials.new("Chair Paint")
    if material.node_tree is None:
        material.use_nodes = True
    mesh.materials.append(material)
    if glossy:
        rough_glossy(material)
    if group:
        node = material.node_tree.nodes.new("ShaderNodeGroup")
        node.name = "user group node"
        node.node_tree = user_group(group)
    if texture:
        image = bpy.data.images.new("tex", 4, 4)
        image.source = "FILE"
        image.filepath = "//tex.png"
        material.node_tree.nodes.new("ShaderNodeTexImage").image = image
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=compress, relative_remap=False)


def inspect(path, out):
    bpy.ops.wm.open_mainfile(filepath=path)
    groups = {
        tree.name: {"tag": tree.get("gloffuse"), "nodes": sorted(n.name for n in tree.nodes)}
        for tree in bpy.data.node_groups if tree.library is None
    }
    materials = {
        m.name: sorted(n.node_tree.name for n in m.node_tree.nodes
                       if n.bl_idname == "ShaderNodeGroup" and n.node_tree is not None)
        for m in bpy.data.materials if m.node_tree is not None
    }
    distributions = {
        m.name: sorted(n.distribution for n in m.node_tree.nodes if hasattr(n, "distribution"))
        for m in bpy.data.materials if m.node_tree is not None
    }
    report = {
        "distributions": distributions,
        "version": list(bpy.data.version),
        "images": {image.name: image.filepath for image in bpy.data.images},
        "groups": groups,
        "materials": materials,
        "scene_tags": [scene.get("gloffuse") for scene in bpy.data.scenes],
        "objects": len(bpy.data.objects),
    }
    with open(out, "w", encoding="utf-8") as f:
        json.dump(report, f, indent=1, sort_keys=True)


def main():
    options = args()
    try:
        if options.make:
            make(options.make, options.group, options.texture, options.compress, options.glossy)
        else:
            inspect(options.inspect, options.out)
    except Exception:
        traceback.print_exc()
        sys.stdout.flush()
        sys.exit(1)
    sys.stdout.flush()


main()
