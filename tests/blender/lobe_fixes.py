"""The lobes Blender leaves short (anisotropic glossy, rough Glass and Refraction), a furnace
with rings and a lit scene to judge what `gloffuse audit --fix` makes of them. Written for
the tests without any of gloffuse's code: it imports nothing of gloffuse_blender.

    blender -b --python lobe_fixes.py -- make --out DIR
    blender -b --python lobe_fixes.py -- furnace --file F.blend --out F.json [--samples N]
    blender -b --python lobe_fixes.py -- lit --file F.blend --out F.json [--samples N]

`make` writes DIR/lobes.blend: one white material per lobe, each on a cube of its own, and
DIR/lobes.json (the Blender version and the material names).

`furnace` renders each material alone: a closed smooth UV sphere of radius 1 at the origin
(128 segments, 64 rings) seen from the front by an orthographic camera, in a white world of
strength 1 on an opaque film, Cycles on the CPU, 128 bounces of every kind, no caustic
tricks, no glossy filter, a box pixel filter of 1 px. Each pixel whose centre lies on the disc
has a view cosine mu = sqrt(1 - d^2) (d its distance from the centre over the radius). It
writes per material the disc's mean (pixels with mu >= 0.1; the outermost are partly world)
and the mean of each ring of mu: [0.1, 0.3) (the rim), [0.3, 0.5), [0.5, 0.7), [0.7, 0.9),
[0.9, 1], each with its standard error from the pixels' spread.

`lit` renders each material on the same sphere in a lit scene: a sky (a blue-white gradient by
height), a sun from above and the side, a perspective camera. It writes per material the
luminance of every pixel (row by row) and the sphere's mask, for the test to compare the
material before and after a fix (the film is transparent, so alpha is the sphere's mask).
"""
import argparse
import json
import math
import os
import sys

import bpy

WHITE = (1.0, 1.0, 1.0, 1.0)
RADIUS = 1.0
ORTHO_SCALE = 2.2  # the sphere fills 2 / 2.2 of the frame
RINGS = (0.1, 0.3, 0.5, 0.7, 0.9, 1.0 + 1e-9)


def version():
    return tuple(bpy.app.version[:2])


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("mode", choices=("make", "furnace", "lit"))
    parser.add_argument("--out", required=True)
    parser.add_argument("--file")
    parser.add_argument("--samples", type=int, default=128)
    parser.add_argument("--resolution", type=int, default=96)
    return parser.parse_args(argv)


# --- the lobes -------------------------------------------------------------------------

def new_material(name, index):
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    output.target = "ALL"
    bpy.ops.mesh.primitive_cube_add(location=(3.0 * index, 0.0, 0.0))
    bpy.context.object.data.materials.append(material)
    return material.node_tree, output


def anisotropic(tree, distribution, roughness, anisotropy, rotation=0.0):
    """A white anisotropic glossy lobe: 3.x's Anisotropic BSDF, 4.0+'s Glossy BSDF."""
    idname = "ShaderNodeBsdfAnisotropic" if version() < (4, 0) else "ShaderNodeBsdfGlossy"
    node = tree.nodes.new(idname)
    node.distribution = distribution
    node.inputs["Color"].default_value = WHITE
    node.inputs["Roughness"].default_value = roughness
    node.inputs["Anisotropy"].default_value = anisotropy
    node.inputs["Rotation"].default_value = rotation
    return node


def dielectric(tree, idname, distribution, roughness, ior):
    node = tree.nodes.new(idname)
    node.distribution = distribution
    node.inputs["Color"].default_value = WHITE
    node.inputs["Roughness"].default_value = roughness
    node.inputs["IOR"].default_value = ior
    return node


def bumped(tree, node):
    """A noise bump into the node's Normal."""
    noise = tree.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 6.0
    bump = tree.nodes.new("ShaderNodeBump")
    bump.inputs["Strength"].default_value = 0.3
    bump.inputs["Distance"].default_value = 0.1
    tree.links.new(noise.outputs["Fac"], bump.inputs["Height"])
    tree.links.new(bump.outputs["Normal"], node.inputs["Normal"])
    return node


LOBES = (
    ("aniso-ggx", lambda t: anisotropic(t, "GGX", 0.7, 0.9, rotation=0.125)),
    ("aniso-ggx-bump", lambda t: bumped(t, anisotropic(t, "GGX", 0.6, 0.8))),
    ("aniso-multiscatter", lambda t: anisotropic(t, "MULTI_GGX", 0.7, 0.9)),
    ("aniso-beckmann", lambda t: anisotropic(t, "BECKMANN", 0.6, 0.8)),
    ("glass-ggx", lambda t: dielectric(t, "ShaderNodeBsdfGlass", "GGX", 0.7, 1.5)),
    # Blender's own conserving glass (a reference for the fixed glass-ggx, not a lobe to fix).
    ("glass-ggx-multiscatter",
     lambda t: dielectric(t, "ShaderNodeBsdfGlass", "MULTI_GGX", 0.7, 1.5)),
    ("glass-beckmann", lambda t: dielectric(t, "ShaderNodeBsdfGlass", "BECKMANN", 0.5, 1.33)),
    ("refraction-ggx", lambda t: dielectric(t, "ShaderNodeBsdfRefraction", "GGX", 0.5, 1.33)),
    ("refraction-beckmann",
     lambda t: dielectric(t, "ShaderNodeBsdfRefraction", "BECKMANN", 0.4, 1.45)),
)


def make(directory):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.filepaths.save_version = 0
    bpy.context.scene.render.engine = "CYCLES"
    for index, (name, build) in enumerate(LOBES):
        tree, output = new_material(name, index)
        tree.links.new(build(tree).outputs[0], output.inputs["Surface"])
    os.makedirs(directory, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(directory, "lobes.blend"))
    with open(os.path.join(directory, "lobes.json"), "w") as out:
        json.dump({"blender_version": bpy.app.version_string,
                   "materials": [name for name, _ in LOBES]}, out, indent=1)


# --- the scenes ---------------------------------------------------------------------------

def sphere(material):
    import bmesh
    mesh = bpy.data.meshes.new("Sphere " + material.name)
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")
    bmesh.ops.create_uvsphere(bm, u_segments=128, v_segments=64, radius=RADIUS, calc_uvs=True)
    bm.to_mesh(mesh)
    bm.free()
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    if hasattr(mesh, "use_auto_smooth"):
        mesh.use_auto_smooth = False
    obj = bpy.data.objects.new("Sphere " + material.name, mesh)
    obj.data.materials.append(material)
    return obj


def scene_for(material, samples, resolution):
    scene = bpy.data.scenes.new("Judge " + material.name)
    scene.collection.objects.link(sphere(material))
    render = scene.render
    render.engine = "CYCLES"
    render.resolution_x = render.resolution_y = resolution
    render.resolution_percentage = 100
    render.film_transparent = False
    render.filter_size = 1.0
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.seed = 7
    cycles.use_denoising = False
    if hasattr(cycles, "use_adaptive_sampling"):
        cycles.use_adaptive_sampling = False
    cycles.blur_glossy = 0.0
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.pixel_filter_type = "BOX"
    for key in ("max_bounces", "glossy_bounces", "transmission_bounces",
                "transparent_max_bounces", "diffuse_bounces", "volume_bounces"):
        setattr(cycles, key, 128)
    cycles.caustics_reflective = cycles.caustics_refractive = True
    return scene


def camera(scene, orthographic):
    data = bpy.data.cameras.new("Camera")
    if orthographic:
        data.type = "ORTHO"
        data.ortho_scale = ORTHO_SCALE
        location, rotation = (0.0, -10.0, 0.0), (math.pi / 2.0, 0.0, 0.0)
    else:
        data.lens = 50.0
        location, rotation = (0.0, -6.0, 1.0), (math.radians(80.5), 0.0, 0.0)
    obj = bpy.data.objects.new("Camera", data)
    obj.location = location
    obj.rotation_euler = rotation
    scene.collection.objects.link(obj)
    scene.camera = obj


def white_world():
    world = bpy.data.worlds.new("White")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = WHITE
    background.inputs["Strength"].default_value = 1.0
    return world


def sky_world():
    """A sky by height: white-blue at the horizon, deeper blue above, dark ground."""
    world = bpy.data.worlds.new("Sky")
    world.use_nodes = True
    tree = world.node_tree
    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    separate = tree.nodes.new("ShaderNodeSeparateXYZ")
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].position = 0.45
    ramp.color_ramp.elements[0].color = (0.15, 0.13, 0.1, 1.0)
    ramp.color_ramp.elements[1].position = 1.0
    ramp.color_ramp.elements[1].color = (0.2, 0.4, 1.0, 1.0)
    middle = ramp.color_ramp.elements.new(0.5)
    middle.color = (0.9, 0.95, 1.0, 1.0)
    half = tree.nodes.new("ShaderNodeMath")
    half.operation = "MULTIPLY_ADD"
    half.inputs[1].default_value = 0.5
    half.inputs[2].default_value = 0.5
    tree.links.new(coordinates.outputs["Generated"], separate.inputs[0])
    tree.links.new(separate.outputs["Z"], half.inputs[0])
    tree.links.new(half.outputs[0], ramp.inputs["Fac"])
    tree.links.new(ramp.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    return world


def sun(scene):
    data = bpy.data.lights.new("Sun", "SUN")
    data.energy = 3.0
    data.angle = math.radians(2.0)
    obj = bpy.data.objects.new("Sun", data)
    obj.rotation_euler = (math.radians(40.0), 0.0, math.radians(35.0))
    scene.collection.objects.link(obj)


def render_pixels(scene, path):
    """The render's luminance (the mean of R, G, B) and alpha, row by row."""
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True, scene=scene.name)
    image = bpy.data.images.load(path)
    values = list(image.pixels[:])
    width, height = image.size
    bpy.data.images.remove(image)
    os.remove(path)
    pixels = range(0, 4 * width * height, 4)
    return ([(values[i] + values[i + 1] + values[i + 2]) / 3.0 for i in pixels],
            [values[i + 3] for i in pixels], width, height)


def rings_of(pixels, width, height):
    """The disc's mean and its rings' (mean, standard error, pixels) by view cosine."""
    radius = (width / 2.0) * (2.0 * RADIUS / ORTHO_SCALE)
    values = [[] for _ in RINGS[:-1]]
    for y in range(height):
        for x in range(width):
            d = math.hypot(x + 0.5 - width / 2.0, y + 0.5 - height / 2.0) / radius
            if d >= 1.0:
                continue
            mu = math.sqrt(1.0 - d * d)
            for k in range(len(RINGS) - 1):
                if RINGS[k] <= mu < RINGS[k + 1]:
                    values[k].append(pixels[y * width + x])
    rings = []
    for ring in values:
        n = len(ring)
        mean = sum(ring) / n
        variance = sum((v - mean) ** 2 for v in ring) / (n - 1)
        rings.append({"mu": None, "mean": mean, "se": math.sqrt(variance / n), "pixels": n})
    for k, ring in enumerate(rings):
        ring["mu"] = [RINGS[k], min(RINGS[k + 1], 1.0)]
    everything = [v for ring in values for v in ring]
    mean = sum(everything) / len(everything)
    variance = sum((v - mean) ** 2 for v in everything) / (len(everything) - 1)
    # The disc's pixels are not alike (rings differ), so this overstates its noise.
    return {"mean": mean, "se": math.sqrt(variance / len(everything)), "rings": rings}


def each_material(path, out, judge):
    bpy.ops.wm.open_mainfile(filepath=path)
    directory = os.path.dirname(os.path.abspath(out))
    results = {}
    for material in list(bpy.data.materials):
        if material.node_tree is None or material.users == 0:
            continue
        exr = os.path.join(directory, "judge-%d.exr" % len(results))
        results[material.name] = judge(material, exr)
    with open(out, "w") as handle:
        json.dump(results, handle)


def furnace(path, out, samples, resolution):
    def judge(material, exr):
        scene = scene_for(material, samples, resolution)
        scene.world = white_world()
        camera(scene, orthographic=True)
        pixels, _, width, height = render_pixels(scene, exr)
        return rings_of(pixels, width, height)
    each_material(path, out, judge)


def lit(path, out, samples, resolution):
    def judge(material, exr):
        scene = scene_for(material, samples, resolution)
        scene.world = sky_world()
        sun(scene)
        camera(scene, orthographic=False)
        # The world lights the sphere but the film shows only it: alpha is its mask.
        scene.render.film_transparent = True
        pixels, alpha, width, height = render_pixels(scene, exr)
        return {"pixels": pixels, "alpha": alpha, "width": width, "height": height}
    each_material(path, out, judge)


def main():
    a = args()
    if a.mode == "make":
        make(a.out)
    elif a.mode == "furnace":
        furnace(a.file, a.out, a.samples, a.resolution)
    else:
        lit(a.file, a.out, a.samples, a.resolution)


if __name__ == "__main__":
    try:
        main()
    except Exception:
        import traceback
        traceback.print_exc()
        sys.exit(1)
