"""The audit tests' own library of user materials (the oracle's input for `gloffuse audit`),
made inside real Blender independently of gloffuse's package: it imports nothing of
gloffuse_blender, and every expectation below is decided from physics, not from running
the audit.

    blender -b --factory-startup -noaudio --python-exit-code 1 --python audit_library.py -- \
        --out DIR [--gloffuse-library LIB.blend]
    python3 audit_library.py --out DIR ...   (bpy module)

It writes into DIR:
  rules.blend                 for each rule of the audit's table that can exist in this
                              Blender, materials that fire it and materials that do not
  nested/deeper/nested.blend  a Glossy Beckmann inside a group inside a group, and an
                              unreachable Glossy GGX that must not be flagged
  unusual.blend               a missing texture, Emission, Holdout, a volume, an OSL Script
                              node, a clean Diffuse, and a scene with Filter Glossy 1.0
  linked.blend                a local material, one linked from //rules.blend, and one linked
                              from //gone.blend, a library deleted once linked
  corrected.blend             (with --gloffuse-library) materials that already conserve energy:
                              gloffuse's "Gloffuse View (GGX)" group, Blender's Multiscatter GGX
  expected.json               what the audit should find in THIS Blender: per file, per material,
                              the rule ids, each finding's node path, the verdict
                              (ok | loses | creates | error) and why; per file, the scene findings

Blender's scene default for Cycles' Filter Glossy (RNA `cycles.blur_glossy` in 3.4, 4.5 and
5.0 alike) is 1.0, so every scene here sets it to 0 except unusual.blend's.

Furnace numbers quoted in the reasons were confirmed by the author with tiny furnace renders
(a white world of strength 1, one camera-only sphere per material, Cycles CPU, 64 samples,
40 px cells, the sphere's mean inside 0.9 of its radius) in each Blender; they are comments,
the tests judge against the verdicts.
"""
import argparse
import json
import os
import sys
import traceback

import bpy

WHITE = (1.0, 1.0, 1.0, 1.0)


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", required=True)
    parser.add_argument("--gloffuse-library")
    return parser.parse_args(argv)


def version():
    return tuple(bpy.app.version[:2])


# --- building blocks -------------------------------------------------------------------

class Library:
    """One .blend being made: its materials (each on the mesh "Swatches", so each has a user
    and is saved) and what the audit should report for them."""

    def __init__(self):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.context.preferences.filepaths.save_version = 0  # no FILE.blend1 beside a re-saved file
        mesh = bpy.data.meshes.new("Swatches")
        corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
        faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
        mesh.from_pydata(corners, [], faces)
        self.mesh = mesh
        obj = bpy.data.objects.new("Swatches", mesh)
        bpy.context.scene.collection.objects.link(obj)
        self.scene = bpy.context.scene
        self.scene.render.engine = "CYCLES"
        self.scene.cycles.blur_glossy = 0.0
        self.materials = {}
        self.file_findings = []

    def material(self, name, verdict, reason):
        """A new material `name` with an empty node tree and a Material Output (target All),
        expected to be judged `verdict`; returns (material, nodes, output)."""
        material = bpy.data.materials.new(name)
        if material.node_tree is None:
            material.use_nodes = True
        nodes = material.node_tree.nodes
        nodes.clear()
        output = nodes.new("ShaderNodeOutputMaterial")
        output.name = "Material Output"
        output.target = "ALL"
        output.is_active_output = True
        self.mesh.materials.append(material)
        self.materials[name] = {"verdict": verdict, "reason": reason, "findings": [], "library": None}
        return material, nodes, output

    def expect(self, material, rule, *path):
        """The audit should report `rule` on the node at material ▸ path (node names)."""
        self.materials[material.name]["findings"].append({"rule": rule, "node": [material.name, *path]})

    def save(self, path):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        bpy.ops.wm.save_as_mainfile(filepath=path, relative_remap=False)
        for entry in self.materials.values():
            entry["rules"] = sorted({f["rule"] for f in entry["findings"]})
        return {"file_findings": self.file_findings, "materials": self.materials}


def link(tree, a, b):
    tree.links.new(a, b)


def surface(material, output, socket):
    link(material.node_tree, socket, output.inputs["Surface"])


def glossy(nodes, name, distribution, roughness, color=WHITE, anisotropy=None, idname="ShaderNodeBsdfGlossy"):
    """A Glossy BSDF (4.0+: the Glossy node is the former Anisotropic one, and a new one
    defaults to Multiscatter GGX, so the distribution is always set)."""
    node = nodes.new(idname)
    node.name = name
    node.distribution = distribution
    node.inputs["Color"].default_value = color
    node.inputs["Roughness"].default_value = roughness
    if anisotropy is not None:
        node.inputs["Anisotropy"].default_value = anisotropy
    return node


def diffuse(nodes, name="Diffuse BSDF", color=WHITE):
    node = nodes.new("ShaderNodeBsdfDiffuse")
    node.name = name
    node.inputs["Color"].default_value = color
    return node


def principled(nodes, distribution, roughness, metallic=0.0):
    node = nodes.new("ShaderNodeBsdfPrincipled")
    node.name = "Principled BSDF"
    node.distribution = distribution
    node.inputs["Base Color"].default_value = WHITE
    node.inputs["Roughness"].default_value = roughness
    node.inputs["Metallic"].default_value = metallic
    return node


def new_group(name, inputs, outputs):
    """A user's shader node group with these (name, socket type) inputs and outputs, and its
    Group Input and Group Output nodes."""
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    for in_out, sockets in (("INPUT", inputs), ("OUTPUT", outputs)):
        for socket_name, socket_type in sockets:
            if hasattr(tree, "interface"):
                tree.interface.new_socket(socket_name, in_out=in_out, socket_type=socket_type)
            elif in_out == "INPUT":
                tree.inputs.new(socket_type, socket_name)
            else:
                tree.outputs.new(socket_type, socket_name)
    group_in = tree.nodes.new("NodeGroupInput")
    group_out = tree.nodes.new("NodeGroupOutput")
    group_out.is_active_output = True
    return tree, group_in, group_out


# --- rules.blend -------------------------------------------------------------------------

def rules_file(path):
    lib = Library()
    v = version()
    pre4 = v < (4, 0)

    # Glossy BSDF: single-scatter GGX, Beckmann and Ashikhmin-Shirley lose energy at rough
    # settings; Multiscatter GGX and roughness 0 do not.
    m, n, out = lib.material("glossy-ggx-r1", "loses",
                             "a white single-scatter GGX at r=1 keeps ~40 % (integrator E_avg 0.409 in 4.x/5.0, "
                             "0.377 in 3.4; furnace 0.37 / 0.35), its Multiscatter GGX twin 1.00")
    surface(m, out, glossy(n, "Glossy BSDF", "GGX", 1.0).outputs[0])
    lib.expect(m, "glossy-single-scatter", "Glossy BSDF")

    m, n, out = lib.material("glossy-ggx-r005", "ok",
                             "GGX at r=0.05 (alpha 0.0025) loses far less than 1 %: the rule fires, "
                             "the furnace sees no loss")
    surface(m, out, glossy(n, "Glossy BSDF", "GGX", 0.05).outputs[0])
    lib.expect(m, "glossy-single-scatter", "Glossy BSDF")

    m, n, out = lib.material("glossy-ggx-r0", "ok", "a perfect mirror (r=0) reflects everything")
    surface(m, out, glossy(n, "Glossy BSDF", "GGX", 0.0).outputs[0])

    m, n, out = lib.material("glossy-multi-ggx-r1", "ok", "Multiscatter GGX conserves energy (~100 %)")
    surface(m, out, glossy(n, "Glossy BSDF", "MULTI_GGX", 1.0).outputs[0])

    m, n, out = lib.material("glossy-ggx-linked-roughness", "loses",
                             "GGX with roughness linked from a Value node (0.8): the rule fires on the "
                             "link; r=0.8 keeps ~58 % (furnace 0.57-0.58), the Multiscatter twin 1.00")
    g = glossy(n, "Glossy BSDF", "GGX", 0.0)
    value = n.new("ShaderNodeValue")
    value.name = "Roughness value"
    value.outputs[0].default_value = 0.8
    link(m.node_tree, value.outputs[0], g.inputs["Roughness"])
    surface(m, out, g.outputs[0])
    lib.expect(m, "glossy-single-scatter", "Glossy BSDF")

    m, n, out = lib.material("glossy-beckmann-r1", "loses",
                             "a white Beckmann at r=1 keeps ~62 % (furnace 0.62 in 3.4, 4.5, 5.0); the Gloffuse "
                             "Multiscatter (Beckmann) twin ~100 %")
    surface(m, out, glossy(n, "Glossy BSDF", "BECKMANN", 1.0).outputs[0])
    lib.expect(m, "glossy-single-scatter", "Glossy BSDF")

    m, n, out = lib.material("glossy-ashikhmin-shirley-r1", "loses",
                             "a white Ashikhmin-Shirley at r=1 keeps ~19 % (furnace 0.19 in 3.4, 4.5, 5.0); the "
                             "Gloffuse Multiscatter (Ashikhmin-Shirley) twin ~100 %")
    surface(m, out, glossy(n, "Glossy BSDF", "ASHIKHMIN_SHIRLEY", 1.0).outputs[0])
    lib.expect(m, "glossy-single-scatter", "Glossy BSDF")

    # A user's groups are scanned whatever their name: gloffuse knows its own by their tag
    # and a fingerprint of their content, so neither a gloffuse-like name nor a bare tag
    # hides a lossy lobe.
    for material_name, group_name, tagged in (
            ("user-group-named-gloffuse", "Gloffuse (GGX)", False),
            ("user-group-tagged", "Brightness Correction (tagged)", True)):
        tree, _, group_out = new_group(group_name, [], [("BSDF", "NodeSocketShader")])
        if tagged:
            tree["gloffuse"] = "0.1.0"
            tree["gloffuse_content"] = "0" * 64
        link(tree, glossy(tree.nodes, "Glossy BSDF", "GGX", 1.0).outputs[0], group_out.inputs[0])
        m, n, out = lib.material(material_name, "loses",
                                 "a user's group %r holding a white single-scatter GGX at r=1 "
                                 "(~40 %%, as glossy-ggx-r1); its twin with Multiscatter GGX 1.00"
                                 % group_name)
        node = n.new("ShaderNodeGroup")
        node.node_tree = tree
        node.name = group_name
        surface(m, out, node.outputs[0])
        lib.expect(m, "glossy-single-scatter", group_name, "Glossy BSDF")

    if pre4:
        m, n, out = lib.material("glossy-sharp", "ok", "3.x's Sharp distribution is a perfect mirror")
        surface(m, out, glossy(n, "Glossy BSDF", "SHARP", 0.5).outputs[0])

        m, n, out = lib.material("anisotropic-ggx-r1", "loses",
                                 "3.x's Anisotropic BSDF, single-scatter GGX r=1, anisotropy 0.5: keeps "
                                 "~50 % (furnace 0.50), its Gloffuse Anisotropic (GGX) twin ~100 %")
        surface(m, out, glossy(n, "Anisotropic BSDF", "GGX", 1.0, anisotropy=0.5,
                               idname="ShaderNodeBsdfAnisotropic").outputs[0])
        lib.expect(m, "glossy-single-scatter", "Anisotropic BSDF")

    # Multiscatter GGX with anisotropy: 3.x's Multiscatter GGX is a random walk that handles
    # anisotropy (no rule); from 4.0 Cycles compensates it with the isotropic albedo table
    # (the rule fires). 4.5 and 5.0 render it at 0.905 (r=0.5, anisotropy 0.5): it loses
    # beside its Gloffuse Anisotropic (GGX) twin.
    name = "anisotropic-multi-ggx-a05"
    if pre4:
        m, n, out = lib.material(name, "ok", "3.x's random-walk Multiscatter GGX conserves energy "
                                             "with anisotropy 0.5")
        surface(m, out, glossy(n, "Anisotropic BSDF", "MULTI_GGX", 0.5, anisotropy=0.5,
                               idname="ShaderNodeBsdfAnisotropic").outputs[0])
    else:
        m, n, out = lib.material(name, "loses", "4.x compensates anisotropic Multiscatter GGX with "
                                                "the isotropic table: furnace 0.905, a loss "
                                                "its Gloffuse Anisotropic twin restores")
        surface(m, out, glossy(n, "Glossy BSDF", "MULTI_GGX", 0.5, anisotropy=0.5).outputs[0])
        lib.expect(m, "anisotropic-multiscatter", "Glossy BSDF")

    # Metallic BSDF (4.3+): white Base Color and Edge Tint make the F82 Fresnel 1.
    if hasattr(bpy.types, "ShaderNodeBsdfMetallic"):
        for distribution, verdict, reason in (
            ("GGX", "loses", "a white Metallic GGX at r=1 is a white GGX conductor: furnace 0.37, "
                             "its Multiscatter twin 1.00"),
            ("MULTI_GGX", "ok", "Metallic Multiscatter GGX conserves energy (~100 %)"),
        ):
            label = {"GGX": "ggx", "MULTI_GGX": "multi-ggx"}[distribution]
            m, n, out = lib.material("metallic-%s-r1" % label, verdict, reason)
            metal = n.new("ShaderNodeBsdfMetallic")
            metal.name = "Metallic BSDF"
            metal.distribution = distribution
            metal.inputs["Base Color"].default_value = WHITE
            metal.inputs["Edge Tint"].default_value = WHITE
            metal.inputs["Roughness"].default_value = 1.0
            surface(m, out, metal.outputs[0])
            if distribution == "GGX":
                lib.expect(m, "metallic-single-scatter", "Metallic BSDF")

    # Glass and Refraction.
    for distribution, verdict, reason in (
        ("GGX", "loses", "a white single-scatter GGX glass at r=1 loses light at each interface "
                         "event: furnace 0.82; its Multiscatter GGX twin 1.00"),
        ("MULTI_GGX", "ok", "Multiscatter GGX glass conserves energy (~100 %)"),
    ):
        label = {"GGX": "ggx", "MULTI_GGX": "multi-ggx"}[distribution]
        m, n, out = lib.material("glass-%s-r1" % label, verdict, reason)
        glass = n.new("ShaderNodeBsdfGlass")
        glass.name = "Glass BSDF"
        glass.distribution = distribution
        glass.inputs["Color"].default_value = WHITE
        glass.inputs["Roughness"].default_value = 1.0
        glass.inputs["IOR"].default_value = 1.5
        surface(m, out, glass.outputs[0])
        if distribution == "GGX":
            lib.expect(m, "glass-single-scatter", "Glass BSDF")

    for roughness, label in ((0.5, "r05"), (0.0, "r0")):
        fires = roughness > 0
        m, n, out = lib.material(
            "refraction-ggx-%s" % label, "loses" if fires else "ok",
            "rough single-scatter refraction loses light; its Gloffuse Refraction (GGX) twin "
            "restores it" if fires else
            "smooth refraction (r=0): no rule; never above 100 %")
        refraction = n.new("ShaderNodeBsdfRefraction")
        refraction.name = "Refraction BSDF"
        refraction.distribution = "GGX"
        refraction.inputs["Color"].default_value = WHITE
        refraction.inputs["Roughness"].default_value = roughness
        refraction.inputs["IOR"].default_value = 1.5
        surface(m, out, refraction.outputs[0])
        if fires:
            lib.expect(m, "refraction-single-scatter", "Refraction BSDF")

    # Principled BSDF, white Base Color: before 4.0 its specular layer is added on top of the
    # full diffuse (white renders at 105-106 % at r=0.3-0.5 in 3.4's furnace), whatever the
    # distribution; from 4.0 it is layered and conserving with Multiscatter GGX. r=0.3 keeps
    # 4.x's GGX loss far from the tolerance (furnace 0.999 vs 1.000; at r=0.5 0.993).
    if pre4:
        m, n, out = lib.material("principled-white-ggx", "creates",
                                 "3.x's Principled adds its specular on top of a white diffuse: "
                                 "> 100 % (furnace 1.047)")
        surface(m, out, principled(n, "GGX", 0.3).outputs[0])
        lib.expect(m, "principled-single-scatter", "Principled BSDF")
        lib.expect(m, "principled-creates-energy", "Principled BSDF")

        m, n, out = lib.material("principled-white-multi-ggx", "creates",
                                 "3.x's Principled creates energy with Multiscatter GGX too (diffuse "
                                 "not reduced by the specular's reflectance; furnace 1.047)")
        surface(m, out, principled(n, "MULTI_GGX", 0.3).outputs[0])
        lib.expect(m, "principled-creates-energy", "Principled BSDF")
    else:
        m, n, out = lib.material("principled-white-ggx", "ok",
                                 "4.x's dielectric Principled at r=0.3: its GGX specular (F0 0.04) loses "
                                 "~0.1 % (furnace 0.999 vs 1.000); the rule fires, the verdict is ok")
        surface(m, out, principled(n, "GGX", 0.3).outputs[0])
        lib.expect(m, "principled-single-scatter", "Principled BSDF")

        m, n, out = lib.material("principled-white-multi-ggx", "ok",
                                 "4.x's layered Principled with Multiscatter GGX conserves energy (1.000)")
        surface(m, out, principled(n, "MULTI_GGX", 0.3).outputs[0])

    m, n, out = lib.material("principled-metal-ggx-r1", "loses",
                             "a white metallic Principled, single-scatter GGX r=1: furnace 0.35 (3.4), "
                             "0.37 (4.5, 5.0); its Multiscatter GGX twin ~100 %")
    surface(m, out, principled(n, "GGX", 1.0, metallic=1.0).outputs[0])
    lib.expect(m, "principled-single-scatter", "Principled BSDF")
    if pre4:
        # Metallic is not constant 0: no Layered twin for this rule, the GGX twin still applies.
        lib.expect(m, "principled-creates-energy", "Principled BSDF")

    # Mix Shader layering a Diffuse and a Glossy by a Fresnel or Layer Weight factor.
    m, n, out = lib.material("mix-fresnel-ggx-r1", "loses",
                             "Fresnel (IOR 1.5) mix of white Diffuse and white GGX r=1: the glossy "
                             "share keeps ~40 %: furnace 0.966 in 3.4, 4.5, 5.0; the Layered twin ~100 %")
    mix = n.new("ShaderNodeMixShader")
    mix.name = "Mix Shader"
    fresnel = n.new("ShaderNodeFresnel")
    fresnel.name = "Fresnel"
    fresnel.inputs["IOR"].default_value = 1.5
    g = glossy(n, "Glossy BSDF", "GGX", 1.0)
    link(m.node_tree, fresnel.outputs[0], mix.inputs[0])
    link(m.node_tree, diffuse(n).outputs[0], mix.inputs[1])
    link(m.node_tree, g.outputs[0], mix.inputs[2])
    surface(m, out, mix.outputs[0])
    lib.expect(m, "mix-fresnel-layering", "Mix Shader")
    lib.expect(m, "glossy-single-scatter", "Glossy BSDF")

    # 3.4 renders Multiscatter GGX high when it shares a shader with other closures (white
    # Diffuse + Multiscatter GGX r=0.5 mixed 50/50: 1.011; two added: 2.075, at 512 samples;
    # alone 1.000), so the "ok" mixes below use a mirror (GGX r=0, no rule) instead.
    m, n, out = lib.material("mix-layer-weight-mirror", "ok",
                             "Layer Weight (Fresnel, blend 0.5) mix of white Diffuse and a white mirror: "
                             "(1-w) + w = 100 % in a white furnace, as the Layered twin")
    mix = n.new("ShaderNodeMixShader")
    mix.name = "Mix Shader"
    weight = n.new("ShaderNodeLayerWeight")
    weight.name = "Layer Weight"
    weight.inputs["Blend"].default_value = 0.5
    reroute = n.new("NodeReroute")
    reroute.name = "Reroute"
    link(m.node_tree, weight.outputs["Fresnel"], reroute.inputs[0])
    link(m.node_tree, reroute.outputs[0], mix.inputs[0])
    link(m.node_tree, glossy(n, "Glossy BSDF", "GGX", 0.0).outputs[0], mix.inputs[1])
    link(m.node_tree, diffuse(n).outputs[0], mix.inputs[2])
    surface(m, out, mix.outputs[0])
    lib.expect(m, "mix-fresnel-layering", "Mix Shader")

    m, n, out = lib.material("mix-constant-fac", "ok",
                             "a Mix Shader with a constant Fac 0.5 of white Diffuse and a white "
                             "mirror: 100 %, no layering")
    mix = n.new("ShaderNodeMixShader")
    mix.name = "Mix Shader"
    mix.inputs[0].default_value = 0.5
    link(m.node_tree, diffuse(n).outputs[0], mix.inputs[1])
    link(m.node_tree, glossy(n, "Glossy BSDF", "GGX", 0.0).outputs[0], mix.inputs[2])
    surface(m, out, mix.outputs[0])

    # Add Shader.
    m, n, out = lib.material("add-two-glossy", "creates",
                             "the sum of two white Multiscatter GGX r=0.5 reflects ~200 % (furnace "
                             "2.00; 3.4 2.07)")
    add = n.new("ShaderNodeAddShader")
    add.name = "Add Shader"
    link(m.node_tree, glossy(n, "Glossy BSDF", "MULTI_GGX", 0.5).outputs[0], add.inputs[0])
    link(m.node_tree, glossy(n, "Glossy BSDF.001", "MULTI_GGX", 0.5).outputs[0], add.inputs[1])
    surface(m, out, add.outputs[0])
    lib.expect(m, "add-reflecting", "Add Shader")

    m, n, out = lib.material("add-emission-diffuse", "ok",
                             "Emission (strength 1) + white Diffuse: ~200 %, but a material with an "
                             "emission finding is not judged for creating energy; no twin")
    add = n.new("ShaderNodeAddShader")
    add.name = "Add Shader"
    emission = n.new("ShaderNodeEmission")
    emission.name = "Emission"
    emission.inputs["Color"].default_value = WHITE
    emission.inputs["Strength"].default_value = 1.0
    link(m.node_tree, emission.outputs[0], add.inputs[0])
    link(m.node_tree, diffuse(n).outputs[0], add.inputs[1])
    surface(m, out, add.outputs[0])
    lib.expect(m, "emission", "Emission")

    # Colours above 1.
    m, n, out = lib.material("diffuse-color-2", "creates", "a Diffuse of colour 2.0 reflects ~200 %")
    surface(m, out, diffuse(n, color=(2.0, 2.0, 2.0, 1.0)).outputs[0])
    lib.expect(m, "color-above-one", "Diffuse BSDF")

    m, n, out = lib.material("diffuse-color-09", "ok", "a Diffuse of colour 0.9 reflects 90 % by design")
    surface(m, out, diffuse(n, color=(0.9, 0.9, 0.9, 1.0)).outputs[0])

    # Toon BSDF (Diffuse component, Size 0.5 = a 45 degree cone): Cycles samples the cone of
    # Size + Smooth and weights each direction by the toon intensity (1 inside Size, falling
    # to 0 across Smooth), so Smooth > 0 loses light and Smooth 0 reflects ~100 %.
    for smooth, label in ((0.5, "smooth05"), (0.0, "smooth0")):
        fires = smooth > 0
        m, n, out = lib.material(
            "toon-diffuse-%s" % label, "loses" if fires else "ok",
            "Toon Smooth 0.5 weights the outer half of its sampling cone below 1: furnace 0.74 (3.4), "
            "0.63 (4.5, 5.0); the twin (Smooth 0) 1.00" if fires else
            "Toon Smooth 0: every sampled direction weighs 1, ~100 %")
        toon = n.new("ShaderNodeBsdfToon")
        toon.name = "Toon BSDF"
        toon.component = "DIFFUSE"
        toon.inputs["Color"].default_value = WHITE
        toon.inputs["Size"].default_value = 0.5
        toon.inputs["Smooth"].default_value = smooth
        surface(m, out, toon.outputs[0])
        if fires:
            lib.expect(m, "toon-smooth", "Toon BSDF")

    return lib.save(path)


# --- nested/deeper/nested.blend ------------------------------------------------------------

def nested_file(path):
    lib = Library()
    inner, _, inner_out = new_group("Inner group", [], [("BSDF", "NodeSocketShader")])
    beckmann = glossy(inner.nodes, "Beckmann glossy", "BECKMANN", 0.6)
    link(inner, beckmann.outputs[0], inner_out.inputs[0])
    # Not connected to the Group Output: never flagged.
    glossy(inner.nodes, "Unused inner glossy", "GGX", 1.0)

    outer, _, outer_out = new_group("Outer group", [], [("BSDF", "NodeSocketShader")])
    inner_node = outer.nodes.new("ShaderNodeGroup")
    inner_node.node_tree = inner
    inner_node.name = "Inner group"
    link(outer, inner_node.outputs[0], outer_out.inputs[0])

    m, n, out = lib.material("nested-beckmann-r06", "loses",
                             "a white Beckmann at r=0.6 two groups deep keeps ~95 % (furnace 0.95 in "
                             "3.4, 4.5, 5.0); the Gloffuse Multiscatter (Beckmann) twin ~100 %")
    outer_node = n.new("ShaderNodeGroup")
    outer_node.node_tree = outer
    outer_node.name = "Outer group"
    reroute = n.new("NodeReroute")
    reroute.name = "Reroute"
    link(m.node_tree, outer_node.outputs[0], reroute.inputs[0])
    surface(m, out, reroute.outputs[0])
    glossy(n, "Unreachable Glossy", "GGX", 1.0)
    lib.expect(m, "glossy-single-scatter", "Outer group", "Inner group", "Beckmann glossy")
    return lib.save(path)


# --- unusual.blend ------------------------------------------------------------------------

OSL_SOURCE = """shader tiny(color Tint = color(0.8), output closure color BSDF = 0)
{
    BSDF = Tint * diffuse(N);
}
"""


def unusual_file(path):
    lib = Library()
    lib.scene.cycles.blur_glossy = 1.0  # Filter Glossy 1.0 (Blender's default)
    lib.file_findings.append({"rule": "filter-glossy", "node": ["scene", lib.scene.name]})

    m, n, out = lib.material("missing-texture", "error",
                             "its Image Texture's file does not exist: the material cannot be judged")
    image = bpy.data.images.new("missing-albedo", 4, 4)
    image.source = "FILE"
    image.filepath = "//textures/missing-albedo.png"
    tex = n.new("ShaderNodeTexImage")
    tex.name = "Image Texture"
    tex.image = image
    d = diffuse(n)
    link(m.node_tree, tex.outputs["Color"], d.inputs["Color"])
    surface(m, out, d.outputs[0])
    lib.expect(m, "missing-texture", "Image Texture")

    m, n, out = lib.material("emission-2", "ok",
                             "Emission strength 2 renders at 200 %, but emitters are not judged for "
                             "creating energy; no twin")
    emission = n.new("ShaderNodeEmission")
    emission.name = "Emission"
    emission.inputs["Color"].default_value = WHITE
    emission.inputs["Strength"].default_value = 2.0
    surface(m, out, emission.outputs[0])
    lib.expect(m, "emission", "Emission")

    m, n, out = lib.material("holdout", "ok", "a Holdout renders nothing to judge (alpha 0): "
                                              "reported, not judged")
    holdout = n.new("ShaderNodeHoldout")
    holdout.name = "Holdout"
    surface(m, out, holdout.outputs[0])
    lib.expect(m, "holdout", "Holdout")

    m, n, out = lib.material("volume-absorption", "ok",
                             "a volume only (no surface) absorbs by design: below 100 %, no twin, "
                             "so neither creates nor loses (furnace 0.86)")
    absorption = n.new("ShaderNodeVolumeAbsorption")
    absorption.name = "Volume Absorption"
    absorption.inputs["Density"].default_value = 0.5
    link(m.node_tree, absorption.outputs[0], out.inputs["Volume"])
    lib.expect(m, "volume", "Material Output")

    m, n, out = lib.material("osl-script", "error",
                             "an OSL Script node (internal): the audit cannot read it, and the SVM "
                             "furnace renders it black (0.00, alpha 1): it could not be audited")
    text = bpy.data.texts.new("tiny.osl")
    text.write(OSL_SOURCE)
    script = n.new("ShaderNodeScript")
    script.name = "Script"
    script.mode = "INTERNAL"
    script.script = text
    # What compiling the script would add (cycles.osl needs an OSL compiler these Blenders
    # lack in background): its closure output.
    if "BSDF" not in script.outputs:
        script.outputs.new("NodeSocketShader", "BSDF")
    surface(m, out, script.outputs["BSDF"])
    lib.expect(m, "unknown-node", "Script")

    m, n, out = lib.material("clean-diffuse", "ok",
                             "a white Diffuse reflects 100 %: the rest of an unusual file is audited")
    surface(m, out, diffuse(n).outputs[0])
    return lib.save(path)


# --- corrected.blend ----------------------------------------------------------------------

VIEW_GROUP = "Gloffuse View (GGX)"


def corrected_file(path, gloffuse_library):
    lib = Library()
    with bpy.data.libraries.load(gloffuse_library, link=False) as (data_from, data_to):
        if VIEW_GROUP not in data_from.node_groups:
            raise RuntimeError("%s holds no node group %r (it has %s)"
                               % (gloffuse_library, VIEW_GROUP, ", ".join(data_from.node_groups)))
        data_to.node_groups = [VIEW_GROUP]
    tree = bpy.data.node_groups[VIEW_GROUP]

    m, n, out = lib.material("corrected-view-ggx-r1", "ok",
                             "gloffuse's own view group (gain 1/E(mu, r)) at r=1, white: every pixel "
                             "~100 %; its tree is gloffuse's, not scanned")
    group = n.new("ShaderNodeGroup")
    group.node_tree = tree
    group.name = "Gloffuse View"
    group.inputs["Color"].default_value = WHITE
    group.inputs["Roughness"].default_value = 1.0
    surface(m, out, group.outputs["BSDF"])

    m, n, out = lib.material("corrected-multi-ggx", "ok", "Blender's own Multiscatter GGX at r=0.7: ~100 %")
    surface(m, out, glossy(n, "Glossy BSDF", "MULTI_GGX", 0.7).outputs[0])
    return lib.save(path)


# --- linked.blend ---------------------------------------------------------------------------

LINKED = "glossy-multi-ggx-r1"
GONE = "gone-glossy"


def gone_file(path):
    """gone.blend: a library that linked.blend links and that is then deleted."""
    lib = Library()
    m, n, out = lib.material(GONE, "error", "")
    surface(m, out, glossy(n, "Glossy BSDF", "MULTI_GGX", 0.5).outputs[0])
    lib.save(path)


def linked_file(path, rules, gone):
    """A local material, one linked from rules.blend (//rules.blend) and one linked from a
    library that no longer exists (//gone.blend, deleted after linking)."""
    lib = Library()
    m, n, out = lib.material("local-diffuse", "ok", "a local white Diffuse: 100 %")
    surface(m, out, diffuse(n).outputs[0])
    bpy.ops.wm.save_as_mainfile(filepath=path, relative_remap=False)  # relative links need a path
    for library, name in ((rules, LINKED), (gone, GONE)):
        with bpy.data.libraries.load(library, link=True, relative=True) as (data_from, data_to):
            data_to.materials = [name]
        lib.mesh.materials.append(bpy.data.materials[name, bpy.data.libraries[os.path.basename(library)].filepath])
    # The finding's node path is the material alone (the material itself is linked). Blender
    # 4.x/5.0 mark the missing library and its placeholder material `is_missing`; 3.4 has no
    # `is_missing` (the placeholder has no node tree, and the library's file does not exist).
    lib.materials[LINKED] = {"verdict": "ok", "findings": [{"rule": "linked-library", "node": [LINKED]}],
                             "library": "//rules.blend",
                             "reason": "linked from //rules.blend (Multiscatter GGX r=1, 100 %): the "
                                       "audit reports the link, the material conserves energy"}
    lib.materials[GONE] = {"verdict": "error", "findings": [{"rule": "linked-library", "node": [GONE]}],
                           "library": "//gone.blend",
                           "reason": "linked from //gone.blend, which no longer exists: the material "
                                     "cannot be audited"}
    result = lib.save(path)
    os.remove(gone)
    return result


# --- main -----------------------------------------------------------------------------------

def main():
    options = args()
    try:
        out = os.path.abspath(options.out)
        os.makedirs(out, exist_ok=True)
        files = {
            "rules.blend": rules_file(os.path.join(out, "rules.blend")),
            "nested/deeper/nested.blend": nested_file(os.path.join(out, "nested", "deeper", "nested.blend")),
            "unusual.blend": unusual_file(os.path.join(out, "unusual.blend")),
        }
        gone = os.path.join(out, "gone.blend")
        gone_file(gone)
        files["linked.blend"] = linked_file(os.path.join(out, "linked.blend"),
                                            os.path.join(out, "rules.blend"), gone)
        if options.gloffuse_library:
            files["corrected.blend"] = corrected_file(os.path.join(out, "corrected.blend"),
                                                      os.path.abspath(options.gloffuse_library))
        expected = {
            "blender_version": ".".join(str(part) for part in bpy.app.version),
            "version": list(version()),
            # The version ranges this oracle assumes for the rules whose applicability
            # depends on the Blender (the Rust catalogue must agree).
            "rule_versions": {
                "principled-creates-energy": {"from": [3, 0], "before": [4, 0]},
                "anisotropic-multiscatter": {"from": [4, 0], "before": None},
                "metallic-single-scatter": {"from": [4, 3], "before": None},
            },
            "files": files,
        }
        with open(os.path.join(out, "expected.json"), "w", encoding="utf-8") as f:
            json.dump(expected, f, indent=1, sort_keys=True)
    except Exception:
        traceback.print_exc()
        sys.stdout.flush()
        sys.exit(1)
    sys.stdout.flush()


main()
