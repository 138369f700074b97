"""The .blend files of tests/audit_waivers.rs: rough single-scatter GGX materials (each loses
about 60 % in the furnace) waived in every way a studio can, and some not.

    blender -b --factory-startup --python waived_materials.py -- OUT_DIR

writes OUT_DIR/waived.blend (every failing material waived; one with waivers gloffuse
cannot read), OUT_DIR/plain.blend (one material not waived, one half waived) and
OUT_DIR/measured.blend (for the furnace: a waived lobe, and two materials brighter than
100 % through a linked colour, which no rule flags).
"""
import os
import sys

import bpy

PROPERTY = "gloffuse_ignore"


def material(name):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    m.use_fake_user = True
    tree = m.node_tree
    for node in [n for n in tree.nodes if n.bl_idname != "ShaderNodeOutputMaterial"]:
        tree.nodes.remove(node)
    return m, tree, tree.nodes["Material Output"]


def glossy(tree, name="Glossy"):
    node = tree.nodes.new("ShaderNodeBsdfGlossy")
    node.name = name
    node.distribution = "GGX"
    node.inputs["Roughness"].default_value = 1.0
    return node


def rough_ggx(name):
    m, tree, out = material(name)
    node = glossy(tree)
    tree.links.new(node.outputs[0], out.inputs["Surface"])
    return m, node


def group_with_glossy(name):
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    if hasattr(tree, "interface"):
        tree.interface.new_socket("Shader", in_out="OUTPUT", socket_type="NodeSocketShader")
    else:
        tree.outputs.new("NodeSocketShader", "Shader")
    out = tree.nodes.new("NodeGroupOutput")
    tree.links.new(glossy(tree).outputs[0], out.inputs[0])
    return tree


def bright(name):
    """A Diffuse BSDF whose colour, 2 on every channel, comes from an RGB node: it renders
    at 200 % and no rule flags it (color-above-one reads only unlinked colours)."""
    m, tree, out = material(name)
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    rgb = tree.nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (2.0, 2.0, 2.0, 1.0)
    tree.links.new(rgb.outputs[0], diffuse.inputs["Color"])
    tree.links.new(diffuse.outputs[0], out.inputs["Surface"])
    return m


def save(path):
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=False)
    bpy.ops.wm.read_factory_settings(use_empty=True)


def waived(path):
    m, _ = rough_ggx("waived-material")
    m[PROPERTY] = "glossy-single-scatter: the look is signed off"
    _, node = rough_ggx("waived-node")
    node[PROPERTY] = "*: brushed steel, approved"
    m, tree, out = material("waived-group")
    group = tree.nodes.new("ShaderNodeGroup")
    group.name = "Coat"
    group.node_tree = group_with_glossy("Coat group")
    group[PROPERTY] = "toon-smooth: not here; glossy-single-scatter: the shared coat"
    tree.links.new(group.outputs[0], out.inputs["Surface"])
    rough_ggx("waived-config")
    m, tree, out = material("bad-waivers")
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    tree.links.new(diffuse.outputs[0], out.inputs["Surface"])
    m[PROPERTY] = 7
    diffuse[PROPERTY] = {"nested": 1}
    save(path)


def plain(path):
    rough_ggx("not-waived")
    m, tree, out = material("half-waived")
    mix = tree.nodes.new("ShaderNodeMixShader")
    first, second = glossy(tree, "Glossy A"), glossy(tree, "Glossy B")
    first[PROPERTY] = "glossy-single-scatter: only this one"
    tree.links.new(first.outputs[0], mix.inputs[1])
    tree.links.new(second.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], out.inputs["Surface"])
    save(path)


def measured(path):
    m, _ = rough_ggx("glossy-waived")
    m[PROPERTY] = "glossy-single-scatter: the look is signed off"
    bright("bright-star")[PROPERTY] = "*: a light card"
    bright("bright-rule")[PROPERTY] = "color-above-one: the colour is meant"
    save(path)


def main():
    out = sys.argv[-1]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    waived(os.path.join(out, "waived.blend"))
    plain(os.path.join(out, "plain.blend"))
    measured(os.path.join(out, "measured.blend"))


main()
