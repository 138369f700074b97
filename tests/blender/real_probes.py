"""Probe materials built the way real files build them, and a second furnace to judge the
audit on them. Written for the tests without any of gloffuse's code: it imports nothing of
gloffuse_blender.

    python3 real_probes.py make --out DIR            (or blender -b ... --python real_probes.py -- make ...)
    python3 real_probes.py furnace --file F.blend --out F.json [--samples N]

`make` writes DIR/probes.blend, one material per way a real material differs from a lab one
(textured by UV, a named UV map, UV-tangent anisotropy, generated coordinates, colour by
world position, tinted and absorbing glass, transmission, alpha 0.5 and 0, Add with sheen,
an Add that creates, a partly metallic Principled BSDF), each on a cube of its own so it has
a user, and DIR/probes.json: per material what physics says the audit must find:
  "verdict"   ok | loses | creates | "not judged" | null (decided by the second furnace)
  "rules"     rule ids the audit must report on it
  "position"  true: the material reads its place in the world, so a sphere elsewhere sees
              other colours (its mean is not compared, its verdict is)

`furnace` renders each material of F.blend alone, in a scene of its own: a closed smooth UV
sphere of radius 1 at the origin (Blender's own UV sphere: 128 segments, 64 rings, its UV map
"UVMap" plus a copy under every name the material's UV Map, Tangent and Normal Map nodes
name), seen from the front (an orthographic camera on -Y looking along +Y, Z up) in a white
world of strength 1 on an opaque film, Cycles on the CPU, deep bounces. The sphere's mean is
the film's mean over its disc: the image's sum less the world seen around the disc, over the
disc's area (no alpha, no coverage weighting). It writes {material: {"mean": m,
"world": w}} (w: the film's mean over the corners, which must read 1).
"""
import argparse
import json
import math
import os
import sys

import bpy

WHITE = (1.0, 1.0, 1.0, 1.0)


def version():
    return tuple(bpy.app.version[:2])


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("mode", choices=("make", "furnace"))
    parser.add_argument("--out", required=True)
    parser.add_argument("--file")
    parser.add_argument("--samples", type=int, default=64)
    return parser.parse_args(argv)


# --- the probes ----------------------------------------------------------------------

class Probes:
    def __init__(self):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.context.preferences.filepaths.save_version = 0
        self.scene = bpy.context.scene
        self.scene.render.engine = "CYCLES"
        self.scene.cycles.blur_glossy = 0.0
        self.expected = {}

    def material(self, name, verdict, rules=(), position=False, fixed=False):
        material = bpy.data.materials.new(name)
        if material.node_tree is None:
            material.use_nodes = True
        nodes = material.node_tree.nodes
        nodes.clear()
        output = nodes.new("ShaderNodeOutputMaterial")
        output.target = "ALL"
        # Each material on a cube of its own (a user, and a mesh that is not the sphere).
        bpy.ops.mesh.primitive_cube_add(location=(3.0 * len(self.expected), 0.0, 0.0))
        bpy.context.object.data.materials.append(material)
        self.expected[name] = {"verdict": verdict, "rules": sorted(rules), "position": position,
                               "fixed": fixed}
        return material.node_tree, output

    def save(self, directory):
        os.makedirs(directory, exist_ok=True)
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "probes.blend"))
        with open(os.path.join(directory, "probes.json"), "w") as out:
            json.dump({"blender_version": bpy.app.version_string, "materials": self.expected},
                      out, indent=1)


def checker_image(name, squares=8):
    """A packed image of `squares` x `squares` squares, 0.1 and 0.9 grey: read at one texel it
    is one of the two; read by UV it averages about 0.5."""
    size = 64
    image = bpy.data.images.new(name, size, size, float_buffer=False)
    pixels = []
    step = size // squares
    for y in range(size):
        for x in range(size):
            value = 0.9 if ((x // step) + (y // step)) % 2 else 0.1
            pixels.extend((value, value, value, 1.0))
    image.pixels = pixels
    image.pack()
    return image


def texture(tree, image, vector=None):
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    node.interpolation = "Closest"
    if vector is not None:
        tree.links.new(vector, node.inputs["Vector"])
    return node


def diffuse(tree, color=WHITE):
    node = tree.nodes.new("ShaderNodeBsdfDiffuse")
    node.inputs["Color"].default_value = color
    return node


def glossy(tree, distribution, roughness, anisotropy=None):
    """A white Glossy BSDF; with an anisotropy, 3.x's Anisotropic BSDF (4.0 merged it into
    Glossy)."""
    idname = "ShaderNodeBsdfAnisotropic" if anisotropy is not None and version() < (4, 0) \
        else "ShaderNodeBsdfGlossy"
    node = tree.nodes.new(idname)
    node.distribution = distribution
    node.inputs["Color"].default_value = WHITE
    node.inputs["Roughness"].default_value = roughness
    if anisotropy is not None:
        node.inputs["Anisotropy"].default_value = anisotropy
    return node


def sheen(tree):
    """A white sheen lobe: Sheen BSDF (4.0+), Velvet BSDF before."""
    node = tree.nodes.new("ShaderNodeBsdfSheen" if version() >= (4, 0) else "ShaderNodeBsdfVelvet")
    node.inputs["Color"].default_value = WHITE
    return node


def principled(tree, distribution, roughness, metallic=0.0, transmission=0.0, color=WHITE):
    node = tree.nodes.new("ShaderNodeBsdfPrincipled")
    node.distribution = distribution
    node.inputs["Base Color"].default_value = color
    node.inputs["Roughness"].default_value = roughness
    node.inputs["Metallic"].default_value = metallic
    name = "Transmission Weight" if "Transmission Weight" in node.inputs else "Transmission"
    node.inputs[name].default_value = transmission
    return node


def surface(tree, output, node, socket=0):
    tree.links.new(node.outputs[socket], output.inputs["Surface"])


def make(directory):
    p = Probes()
    checker = checker_image("Checker")

    tree, out = p.material("uv-checker", "ok")
    coords = tree.nodes.new("ShaderNodeTexCoord")
    tex = texture(tree, checker, coords.outputs["UV"])
    shader = diffuse(tree)
    tree.links.new(tex.outputs["Color"], shader.inputs["Color"])
    surface(tree, out, shader)

    # A glTF import names its UV map; a sphere without that name reads (0, 0) everywhere.
    tree, out = p.material("uv-map-named", "ok")
    uv = tree.nodes.new("ShaderNodeUVMap")
    uv.uv_map = "TEXCOORD_0"
    tex = texture(tree, checker, uv.outputs["UV"])
    shader = diffuse(tree)
    tree.links.new(tex.outputs["Color"], shader.inputs["Color"])
    surface(tree, out, shader)

    # glTF's anisotropy import: the tangent along the UV map's U.
    tree, out = p.material("uv-tangent-anisotropy", "loses", ["glossy-single-scatter"])
    tangent = tree.nodes.new("ShaderNodeTangent")
    tangent.direction_type = "UV_MAP"
    tangent.uv_map = "TEXCOORD_0"
    shader = glossy(tree, "GGX", 0.5, anisotropy=0.8)
    tree.links.new(tangent.outputs["Tangent"], shader.inputs["Tangent"])
    surface(tree, out, shader)

    # Generated coordinates over the whole object: Z from the bottom to the top.
    tree, out = p.material("generated-gradient", "ok")
    coords = tree.nodes.new("ShaderNodeTexCoord")
    split = tree.nodes.new("ShaderNodeSeparateXYZ")
    shader = diffuse(tree)
    tree.links.new(coords.outputs["Generated"], split.inputs[0])
    tree.links.new(split.outputs["Z"], shader.inputs["Color"])
    surface(tree, out, shader)

    # Colour by world position on a losing lobe: the twin must see the same colours.
    tree, out = p.material("position-colored-glossy", "loses",
                           ["depends-on-scene", "glossy-single-scatter"], position=True)
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    gradient = tree.nodes.new("ShaderNodeTexGradient")
    shader = glossy(tree, "GGX", 1.0)
    tree.links.new(geometry.outputs["Position"], gradient.inputs["Vector"])
    tree.links.new(gradient.outputs["Color"], shader.inputs["Color"])
    surface(tree, out, shader)

    tree, out = p.material("tinted-glass", "ok")
    glass = tree.nodes.new("ShaderNodeBsdfGlass")
    glass.distribution = "MULTI_GGX"
    glass.inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)
    glass.inputs["Roughness"].default_value = 0.1
    glass.inputs["IOR"].default_value = 1.5
    surface(tree, out, glass)

    # An absorbing volume inside a clear surface: a sphere that absorbs must read so.
    tree, out = p.material("absorbing-volume", "ok", ["volume"])
    clear = tree.nodes.new("ShaderNodeBsdfTransparent")
    surface(tree, out, clear)
    absorption = tree.nodes.new("ShaderNodeVolumeAbsorption")
    absorption.inputs["Density"].default_value = 1.0
    absorption.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    tree.links.new(absorption.outputs[0], out.inputs["Volume"])

    # Principled transmission, single scatter: a real loss of a few points on a solid sphere.
    tree, out = p.material("principled-transmission-ggx", "loses", ["principled-single-scatter"])
    surface(tree, out, principled(tree, "GGX", 0.5, transmission=1.0))

    for name, alpha, verdict in (("alpha-05", 0.5, "ok"), ("alpha-0", 0.0, "not judged")):
        tree, out = p.material(name, verdict)
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.inputs[0].default_value = alpha
        tree.links.new(tree.nodes.new("ShaderNodeBsdfTransparent").outputs[0], mix.inputs[1])
        tree.links.new(diffuse(tree).outputs[0], mix.inputs[2])
        surface(tree, out, mix)

    # Sheen over a base through Add: a real material's layering, judged by its brightness.
    tree, out = p.material("add-sheen", None, ["add-reflecting"])
    add = tree.nodes.new("ShaderNodeAddShader")
    tree.links.new(diffuse(tree, (0.7, 0.7, 0.7, 1.0)).outputs[0], add.inputs[0])
    tree.links.new(sheen(tree).outputs[0], add.inputs[1])
    surface(tree, out, add)

    # An Add that creates about 9 points: 0.9 diffuse + 0.2 of a mirror-like lobe.
    tree, out = p.material("add-creates", "creates", ["add-reflecting"])
    add = tree.nodes.new("ShaderNodeAddShader")
    shine = glossy(tree, "MULTI_GGX", 0.3)
    shine.inputs["Color"].default_value = (0.2, 0.2, 0.2, 1.0)
    tree.links.new(diffuse(tree, (0.9, 0.9, 0.9, 1.0)).outputs[0], add.inputs[0])
    tree.links.new(shine.outputs[0], add.inputs[1])
    surface(tree, out, add)

    # Half metal: 3.x adds its specular to an undimmed base, 4.0+ conserves; every
    # Blender has a twin that conserves, so the fix is made.
    tree, out = p.material("principled-metallic-05", "loses",
                           ["principled-single-scatter"], fixed=True)
    surface(tree, out, principled(tree, "GGX", 0.7, metallic=0.5))
    p.save(directory)


# --- the second furnace ---------------------------------------------------------------

RESOLUTION = 256
ORTHO_SCALE = 2.2  # the sphere (radius 1) fills 2 / 2.2 of the frame


def uv_names(tree, seen=()):
    names = set()
    for node in tree.nodes:
        if node.bl_idname in ("ShaderNodeUVMap", "ShaderNodeTangent", "ShaderNodeNormalMap") \
                and getattr(node, "uv_map", ""):
            names.add(node.uv_map)
        if node.bl_idname == "ShaderNodeGroup" and node.node_tree is not None \
                and node.node_tree.name not in seen:
            names |= uv_names(node.node_tree, seen + (node.node_tree.name,))
    return names


def furnace_scene(material, samples):
    scene = bpy.data.scenes.new("Second furnace " + material.name)
    world = bpy.data.worlds.new("White")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = WHITE
    background.inputs["Strength"].default_value = 1.0
    scene.world = world
    mesh = bpy.data.meshes.new("Sphere " + material.name)
    import bmesh
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")
    try:
        bmesh.ops.create_uvsphere(bm, u_segments=128, v_segments=64, radius=1.0, calc_uvs=True)
    except TypeError:  # before 3.0
        bmesh.ops.create_uvsphere(bm, u_segments=128, v_segments=64, diameter=1.0, calc_uvs=True)
    bm.to_mesh(mesh)
    bm.free()
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    if hasattr(mesh, "use_auto_smooth"):
        mesh.use_auto_smooth = False
    for name in sorted(uv_names(material.node_tree) - {"UVMap"}):
        mesh.uv_layers.new(name=name)
    sphere = bpy.data.objects.new("Sphere", mesh)
    sphere.data.materials.append(material)
    scene.collection.objects.link(sphere)
    camera_data = bpy.data.cameras.new("Front")
    camera_data.type = "ORTHO"
    camera_data.ortho_scale = ORTHO_SCALE
    camera = bpy.data.objects.new("Front", camera_data)
    camera.location = (0.0, -10.0, 0.0)
    camera.rotation_euler = (math.pi / 2.0, 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    render = scene.render
    render.engine = "CYCLES"
    render.resolution_x = render.resolution_y = RESOLUTION
    render.resolution_percentage = 100
    render.film_transparent = False
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.use_denoising = False
    if hasattr(cycles, "use_adaptive_sampling"):
        cycles.use_adaptive_sampling = False
    cycles.blur_glossy = 0.0
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    for key in ("max_bounces", "glossy_bounces", "transmission_bounces",
                "transparent_max_bounces"):
        setattr(cycles, key, 128)
    cycles.diffuse_bounces = 16
    cycles.volume_bounces = 16
    cycles.caustics_reflective = cycles.caustics_refractive = True
    return scene


def disc_mean(path):
    image = bpy.data.images.load(path)
    values = list(image.pixels[:])
    width, height = image.size
    bpy.data.images.remove(image)
    total = 0.0
    corner = []
    for y in range(height):
        for x in range(width):
            i = 4 * (y * width + x)
            v = (values[i] + values[i + 1] + values[i + 2]) / 3.0
            total += v
            if (x < 8 or x >= width - 8) and (y < 8 or y >= height - 8):
                corner.append(v)
    radius = RESOLUTION / ORTHO_SCALE  # pixels
    area = math.pi * radius * radius
    world = sum(corner) / len(corner)
    return (total - (width * height - area) * world) / area, world


def furnace(path, out, samples):
    bpy.ops.wm.open_mainfile(filepath=path)
    results = {}
    directory = os.path.dirname(os.path.abspath(out))
    for material in list(bpy.data.materials):
        if material.node_tree is None:
            continue
        scene = furnace_scene(material, samples)
        exr = os.path.join(directory, "second-furnace-%d.exr" % len(results))
        scene.render.filepath = exr
        bpy.ops.render.render(write_still=True, scene=scene.name)
        mean, world = disc_mean(exr)
        os.remove(exr)
        results[material.name] = {"mean": mean, "world": world}
    with open(out, "w") as handle:
        json.dump(results, handle, indent=1)


def main():
    a = args()
    if a.mode == "make":
        make(a.out)
    else:
        furnace(a.file, a.out, a.samples)


if __name__ == "__main__":
    try:
        main()
    except Exception:
        import traceback
        traceback.print_exc()
        sys.exit(1)
