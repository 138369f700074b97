# ---------------------------------------------------------------------------
# gloffuse furnace.py: the white furnace the verify and refresh jobs render.
#
# A white world of strength 1, an orthographic camera looking at a grid of
# white spheres (one cell per sphere, row 0 at the top of the image). A plain
# furnace looks down -Z at domes visible to camera rays only, so that each
# sees nothing but the world. A "solid" furnace (glass, and every material the
# audit renders) holds whole, closed UV spheres with a UV map, seen from the
# side as an object is in a scene (the camera looks along +Y, Z up), visible
# to every ray so that glass has an inside and volumes absorb, each at a depth
# of its own so that light leaving one almost never meets another.
# One Cycles or EEVEE render of the whole grid is written as a single-layer, 32-bit
# float, ZIP-compressed OpenEXR (scene-linear RGBA, premultiplied by coverage
# because the film is transparent). The "furnace" section of the parameter
# document says what to render (furnace_params checks it).
#
# A module of the gloffuse_blender package, used by the furnace job
# (furnace_job.py) and the tests' material scene. Functions and constants only;
# every Blender version difference in the scene goes through compat.py's
# compat_* functions.
# ---------------------------------------------------------------------------
import argparse
import math
import os
import time

import bpy

from .compat import (
    anisotropic_glossy_node,
    compat_camera_rays_only,
    compat_disable_denoising,
    compat_disable_post_processing,
    compat_disable_time_limit,
    compat_eevee_engine,
    compat_eevee_furnace,
    compat_exr_settings,
    compat_node_tree,
    compat_principled_dielectric,
    glossy_node,
)
from .contract import check_fields
from .meshes import sphere_mesh
from .runtime import render_result_image

FURNACE_PLAIN_DISTRIBUTIONS = ("BECKMANN", "GGX", "ASHIKHMIN_SHIRLEY", "MULTI_GGX")
FURNACE_GLASS_DISTRIBUTIONS = ("BECKMANN", "GGX", "MULTI_GGX")
FURNACE_ENGINES = ("cycles", "eevee")

# Each sphere is the upper half (plus one ring) of a UV sphere with this many
# segments and rings (counted on the full sphere). The sphere's mean converges
# to E_avg as 1/rings^2, driven by the radial resolution near the silhouette:
# measured in 4.5 (1024 spp), the GGX/Ashikhmin-Shirley r=1 means come out
# +0.07 % high with 64 rings and within 0.01-0.02 % of a 512 x 256 sphere with
# 128 x 128, at the triangle count of a full 128 x 64 sphere.
FURNACE_SPHERE_SEGMENTS = 128
FURNACE_SPHERE_RINGS = 128

# A solid sphere's UV map (Blender's default name): U around the Z axis, V
# from pole to pole, as a UV sphere Blender adds has.
FURNACE_UV_MAP = "UVMap"

# The camera sits this many grid cells in front of the spheres.
FURNACE_CAMERA_HEIGHT = 10.0

# Blender clamps a render's resolution to this many pixels a side, silently:
# a larger grid would lose its last rows and columns.
FURNACE_MAX_RESOLUTION = 65536

# The most pixels one furnace render may hold: 2^28 (4 GiB of float RGBA in
# Blender's render result, as much again in its passes). 2800 spheres of 1024 px
# fit Blender's side limit but would need 47 GB.
FURNACE_MAX_PIXELS = 1 << 28

# A solid furnace's sphere k sits FURNACE_SOLID_SPACING (k mod
# FURNACE_SOLID_LEVELS) cells behind its grid cell: seen from one sphere
# (radius <= half a cell) the spheres of other depths cover at most
# sum 2 r^2 / (4 (16 k)^2) = 0.08 % of its sky, those of its own depth (256
# cells or more away) less, and they return most of that light anyway. The
# levels bound the depth to 4,080 cells (9,067 units), where a float still
# places a vertex to 0.001 of the sphere's radius: a depth per sphere would
# reach 71,000 units for 2,000 materials.
FURNACE_SOLID_SPACING = 16.0
FURNACE_SOLID_LEVELS = 256

# A solid glass sphere keeps light inside for many bounces, nearly smooth
# dense glass for hundreds (total internal reflection): the GGX group at IOR
# 2.4, roughness 0.1 (Blender 5.0.1) renders 98.6 % with 64, 99.5 % with 256
# and 99.95 % with 1,024, Cycles' largest, which costs little more.
FURNACE_SOLID_BOUNCES = 1024


class FurnaceParamsError(ValueError):
    """The parameter document's "furnace" section is missing or malformed."""


# --- arguments and parameters ------------------------------------------------

def parse_furnace_args(args):
    parser = argparse.ArgumentParser(
        prog="gloffuse-furnace",
        description="Render the gloffuse furnace grid described by the embedded parameters.")
    parser.add_argument("--output", metavar="OUT.exr",
                        help="write the EXR here instead of furnace.output")
    return parser.parse_args(args)


def furnace_require(cond, message):
    if not cond:
        raise FurnaceParamsError("furnace parameters: " + message)


def furnace_number(section, key, kind, low, high=None):
    value = section.get(key)
    furnace_require(isinstance(value, (int, float)) and not isinstance(value, bool),
                    "%r must be a number, got %r" % (key, value))
    furnace_require(kind is float or float(value).is_integer(),
                    "%r must be an integer, got %r" % (key, value))
    value = kind(value)
    furnace_require(value >= low and (high is None or value <= high),
                    "%r = %r is outside [%r, %s]"
                    % (key, value, low, "inf" if high is None else high))
    return value


def furnace_sphere_spec(index, sphere):
    """Check one sphere entry and return a normalised copy. Shaders: "plain" (a
    Glossy BSDF), "group" (a gloffuse shader group, with an "ior" for the
    layered groups), "mix" (what artists build by hand: Mix Shader with a
    Fresnel factor over Diffuse and Glossy), "principled" (Principled BSDF),
    "glass" (a Glass BSDF of the given distribution and "ior") and "diffuse"
    (a Diffuse BSDF: how bright the engine's lighting itself is). A "plain" or
    "group" sphere with an "anisotropy" is anisotropic, its tangent the
    constant world X."""
    where = "spheres[%d]" % index
    furnace_require(isinstance(sphere, dict), "%s must be an object" % where)
    roughness = furnace_number(sphere, "roughness", float, 0.0, 1.0)
    shader = sphere.get("shader")
    spec = {"shader": shader, "roughness": roughness}
    if shader in ("mix", "principled", "glass") or (shader == "group" and "ior" in sphere):
        # gloffuse checks the upper bound (the layered table's last slice).
        spec["ior"] = furnace_number(sphere, "ior", float, 1.0)
    if shader in ("plain", "group") and "anisotropy" in sphere:
        spec["anisotropy"] = furnace_number(sphere, "anisotropy", float, -0.99, 0.99)
    if shader in ("plain", "mix", "glass"):
        distribution = sphere.get("distribution")
        allowed = FURNACE_GLASS_DISTRIBUTIONS if shader == "glass" else FURNACE_PLAIN_DISTRIBUTIONS
        furnace_require(distribution in allowed,
                        "%s.distribution must be one of %s, got %r"
                        % (where, ", ".join(allowed), distribution))
        spec["distribution"] = distribution
        return spec
    if shader == "group":
        group = sphere.get("group")
        furnace_require(isinstance(group, str) and group != "",
                        "%s.group must be a node group name" % where)
        spec["group"] = group
        return spec
    if shader in ("principled", "diffuse"):
        return spec
    raise FurnaceParamsError("furnace parameters: %s.shader must be \"plain\", \"group\", "
                             "\"mix\", \"principled\", \"glass\" or \"diffuse\", got %r"
                             % (where, shader))


def furnace_color(section):
    """The spheres' colour: three numbers in [0, 1] (white when absent)."""
    color = section.get("color", [1.0, 1.0, 1.0])
    furnace_require(isinstance(color, list) and len(color) == 3,
                    "\"color\" must be [r, g, b], got %r" % (color,))
    return tuple(furnace_number({"color": c}, "color", float, 0.0, 1.0) for c in color)


def furnace_params(document):
    """The validated "furnace" section of the parameter document."""
    furnace_require(isinstance(document, dict), "the parameter document must be an object")
    check_fields(document, "furnace_document", "the furnace job's document")
    section = document.get("furnace")
    furnace_require(isinstance(section, dict), "the document has no \"furnace\" object")
    output = section.get("output")
    furnace_require(isinstance(output, str) and output != "", "\"output\" must be a file path")
    spheres = section.get("spheres")
    furnace_require(isinstance(spheres, list) and spheres, "\"spheres\" must be a non-empty list")
    engine = section.get("engine", "cycles")
    furnace_require(engine in FURNACE_ENGINES,
                    "\"engine\" must be one of %s, got %r" % (", ".join(FURNACE_ENGINES), engine))
    solid = section.get("solid", False)
    furnace_require(isinstance(solid, bool), "\"solid\" must be true or false, got %r" % (solid,))
    furnace_require(not solid or engine == "cycles", "a \"solid\" furnace renders in cycles only")
    return {
        "engine": engine,
        "solid": solid,
        "cell": furnace_number(section, "cell", int, 4),
        "columns": furnace_number(section, "columns", int, 1),
        "samples": furnace_number(section, "samples", int, 1),
        "seed": furnace_number(section, "seed", int, 0, 2 ** 31 - 1),  # Cycles' seed range
        "radius_fraction": furnace_number(section, "radius_fraction", float, 0.05, 1.0),
        "color": furnace_color(section),
        "threads": furnace_number(section, "threads", int, 0),
        "output": output,
        "spheres": [furnace_sphere_spec(i, s) for i, s in enumerate(spheres)],
    }


def furnace_grid(furnace):
    """(columns, rows) of the grid; row-major, row 0 at the top."""
    columns = furnace["columns"]
    rows = (len(furnace["spheres"]) + columns - 1) // columns
    return columns, rows


def furnace_layout(cells, cell):
    """(columns, rows) of the about square grid of `cells` cells of `cell`
    pixels: the shape whose longer side is shortest, so the most cells fit in
    FURNACE_MAX_RESOLUTION. A ValueError when even that is too large."""
    columns = math.isqrt(max(cells, 1) - 1) + 1
    rows = (max(cells, 1) + columns - 1) // columns
    side = FURNACE_MAX_RESOLUTION // cell
    if columns > side:
        raise ValueError("%d spheres of %d px need a %d x %d px render, and Blender renders at "
                         "most %d px a side: at most %d spheres fit at this cell size (a smaller "
                         "cell fits more)" % (cells, cell, columns * cell, rows * cell,
                                              FURNACE_MAX_RESOLUTION, side * side))
    if columns * rows * cell * cell > FURNACE_MAX_PIXELS:
        raise ValueError("%d spheres of %d px need a %d x %d px render, and the audit renders "
                         "at most %d pixels at once (%.0f GB of pixels would not fit in "
                         "memory): at most %d spheres fit at this cell size (a smaller cell "
                         "fits more)" % (cells, cell, columns * cell, rows * cell,
                                         FURNACE_MAX_PIXELS, columns * rows * cell * cell * 16e-9,
                                         FURNACE_MAX_PIXELS // (cell * cell)))
    return columns, rows


# --- scene ---------------------------------------------------------------------

def furnace_world():
    world = bpy.data.worlds.new("Gloffuse furnace world")
    tree = compat_node_tree(world)
    tree.nodes.clear()
    background = tree.nodes.new("ShaderNodeBackground")
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = 1.0
    output = tree.nodes.new("ShaderNodeOutputWorld")
    tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    world.color = (1.0, 1.0, 1.0)
    return world


def furnace_sphere_mesh(radius):
    """One smooth-shaded UV dome shared by every sphere object; its single
    material slot is linked per object."""
    # The camera looks down -Z and no other ray sees a sphere, so only the
    # upper half is ever hit: drop the rest (render time grows with the
    # triangle count: Cycles syncs a separate copy of the mesh for every object
    # here, the per-object materials keeping it from instancing).
    # One ring below the equator stays so that the equator's smooth normals
    # stay horizontal.
    below = -radius * math.sin(math.pi / FURNACE_SPHERE_RINGS) * 1.001
    return sphere_mesh("Gloffuse furnace sphere", radius, FURNACE_SPHERE_SEGMENTS,
                       FURNACE_SPHERE_RINGS, cut_below=below)


def furnace_group_output(node):
    if "BSDF" in node.outputs:
        return node.outputs["BSDF"]
    for socket in node.outputs:
        if socket.type == "SHADER":
            return socket
    raise RuntimeError("node group %r has no shader output" % node.node_tree.name)


def furnace_label(sphere):
    if sphere["shader"] == "group":
        label = sphere["group"]
    elif sphere["shader"] == "principled":
        label = "Principled BSDF"
    elif sphere["shader"] == "diffuse":
        label = "Diffuse BSDF"
    elif sphere["shader"] == "glass":
        label = "Glass BSDF %s" % sphere["distribution"]
    else:
        label = "%s %s" % (sphere["shader"], sphere["distribution"])
    if "ior" in sphere:
        label += " IOR %g" % sphere["ior"]
    if "anisotropy" in sphere:
        label += " anisotropy %g" % sphere["anisotropy"]
    return label


def furnace_anisotropy(tree, node, anisotropy):
    """Anisotropy along the constant world X: every pixel of the sphere sees
    the view at another azimuth from it (Cycles' own default, radial about Z,
    is square to a camera looking down -Z everywhere)."""
    tangent = tree.nodes.new("ShaderNodeCombineXYZ")
    tangent.label = "Tangent: world X"
    tangent.inputs["X"].default_value = 1.0
    tree.links.new(tangent.outputs["Vector"], node.inputs["Tangent"])
    node.inputs["Anisotropy"].default_value = anisotropy


def furnace_mix_shader(tree, sphere, color):
    """Mix Shader(Fac = Fresnel(IOR), Diffuse(color), white Glossy): the
    glossy-over-diffuse material artists build by hand."""
    nodes, links = tree.nodes, tree.links
    fresnel = nodes.new("ShaderNodeFresnel")
    fresnel.inputs["IOR"].default_value = sphere["ior"]
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = tuple(color) + (1.0,)
    glossy = glossy_node(nodes, sphere["distribution"])
    glossy.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    glossy.inputs["Roughness"].default_value = sphere["roughness"]
    mix = nodes.new("ShaderNodeMixShader")
    links.new(fresnel.outputs["Fac"], mix.inputs["Fac"])
    links.new(diffuse.outputs["BSDF"], mix.inputs[1])
    links.new(glossy.outputs["BSDF"], mix.inputs[2])
    return mix.outputs["Shader"]


def furnace_material(index, sphere, color):
    """A material of colour `color`: a plain Glossy BSDF of the given
    distribution, a gloffuse shader group, the hand-made Mix Shader, or
    Principled BSDF at its defaults (dielectric, IOR as given)."""
    material = bpy.data.materials.new("Furnace %03d %s r=%g"
                                      % (index, furnace_label(sphere), sphere["roughness"]))
    tree = compat_node_tree(material)
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.target = "ALL"
    if sphere["shader"] == "mix":
        tree.links.new(furnace_mix_shader(tree, sphere, color), output.inputs["Surface"])
        return material
    if sphere["shader"] == "principled":
        node = tree.nodes.new("ShaderNodeBsdfPrincipled")
        compat_principled_dielectric(node, sphere["ior"])
        shader_output = node.outputs["BSDF"]
    elif sphere["shader"] == "diffuse":
        node = tree.nodes.new("ShaderNodeBsdfDiffuse")
        shader_output = node.outputs["BSDF"]
    elif sphere["shader"] == "glass":
        node = tree.nodes.new("ShaderNodeBsdfGlass")
        node.distribution = sphere["distribution"]
        node.inputs["IOR"].default_value = sphere["ior"]
        shader_output = node.outputs["BSDF"]
    elif sphere["shader"] == "plain" and "anisotropy" in sphere:
        node = anisotropic_glossy_node(tree.nodes, sphere["distribution"])
        shader_output = node.outputs["BSDF"]
    elif sphere["shader"] == "plain":
        node = tree.nodes.new("ShaderNodeBsdfGlossy")
        node.distribution = sphere["distribution"]
        shader_output = node.outputs["BSDF"]
    else:
        group = bpy.data.node_groups.get(sphere["group"])
        if group is None:
            raise FurnaceParamsError("furnace parameters: sphere %d uses node group %r, which "
                                     "was not built (groups: %s)"
                                     % (index, sphere["group"],
                                        ", ".join(repr(g.name) for g in bpy.data.node_groups)))
        node = tree.nodes.new("ShaderNodeGroup")
        node.node_tree = group
        shader_output = furnace_group_output(node)
        if "ior" in sphere:
            node.inputs["IOR"].default_value = sphere["ior"]
    if "anisotropy" in sphere:
        furnace_anisotropy(tree, node, sphere["anisotropy"])
    color_input = "Color" if "Color" in node.inputs else "Base Color"
    node.inputs[color_input].default_value = tuple(color) + (1.0,)
    node.inputs["Roughness"].default_value = sphere["roughness"]
    tree.links.new(shader_output, output.inputs["Surface"])
    return material


def furnace_unit(furnace):
    """World units per grid cell: 1 in the plain furnace; in a solid one, what
    makes each sphere's radius 1, as the UV sphere Blender adds (a volume's
    density and a texture's scale are per world unit)."""
    return 2.0 / furnace["radius_fraction"] if furnace.get("solid", False) else 1.0


def furnace_camera(columns, solid, unit):
    """The orthographic camera, `unit` world units per cell: looking down -Z at
    the plain furnace's domes, or along +Y at a solid furnace's spheres (Z up)."""
    data = bpy.data.cameras.new("Gloffuse furnace camera")
    data.type = "ORTHO"
    data.sensor_fit = "HORIZONTAL"
    data.ortho_scale = columns * unit
    data.shift_x = 0.0
    data.shift_y = 0.0
    data.clip_start = 0.1
    depth = FURNACE_SOLID_SPACING * FURNACE_SOLID_LEVELS if solid else 0.0
    data.clip_end = (2.0 * FURNACE_CAMERA_HEIGHT + depth) * unit
    camera = bpy.data.objects.new("Gloffuse furnace camera", data)
    if solid:
        camera.location = (0.0, -FURNACE_CAMERA_HEIGHT * unit, 0.0)
        camera.rotation_euler = (0.5 * math.pi, 0.0, 0.0)  # looks along +Y, +Z up in the image
    else:
        camera.location = (0.0, 0.0, FURNACE_CAMERA_HEIGHT)
        camera.rotation_euler = (0.0, 0.0, 0.0)  # looks down -Z, +Y up in the image
    return camera


def furnace_render_settings(scene, furnace, columns, rows):
    for side, count in (("wide", columns), ("high", rows)):
        if count * furnace["cell"] > FURNACE_MAX_RESOLUTION:
            raise ValueError("a furnace grid %d cells %s at %d px exceeds Blender's %d px limit"
                             % (count, side, furnace["cell"], FURNACE_MAX_RESOLUTION))
    render = scene.render
    render.resolution_x = columns * furnace["cell"]
    render.resolution_y = rows * furnace["cell"]
    render.resolution_percentage = 100
    render.pixel_aspect_x = 1.0
    render.pixel_aspect_y = 1.0
    render.use_border = False
    render.film_transparent = True
    compat_disable_post_processing(render)
    if furnace["threads"] > 0:
        render.threads_mode = "FIXED"
        render.threads = furnace["threads"]
    else:
        render.threads_mode = "AUTO"
    if furnace["engine"] == "eevee":
        render.engine = compat_eevee_engine()
        compat_eevee_furnace(scene, scene.world, furnace["samples"])
    else:
        render.engine = "CYCLES"
        furnace_cycles_settings(scene.cycles, scene, furnace)

    view = scene.view_settings
    scene.display_settings.display_device = "sRGB"
    view.view_transform = "Standard"
    view.look = "None"
    view.exposure = 0.0
    view.gamma = 1.0
    view.use_curve_mapping = False
    compat_exr_settings(render.image_settings)


def furnace_cycles_settings(cycles, scene, furnace):
    """An unbiased, noise-only Cycles render: fixed samples and seed, no
    clamping, no denoising."""
    cycles.device = "CPU"
    cycles.samples = furnace["samples"]
    cycles.seed = furnace["seed"]
    cycles.use_animated_seed = False
    cycles.use_adaptive_sampling = False
    compat_disable_time_limit(cycles)
    # Clamping would bias the estimate; 0 disables it.
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    compat_disable_denoising(scene)
    if furnace.get("solid", False):
        # Light crosses a glass sphere's surfaces many times: enough bounces of
        # every kind, and no Filter Glossy (it widens the lobes after the first).
        for kind in ("max", "glossy", "transmission", "transparent_max"):
            setattr(cycles, kind + "_bounces", FURNACE_SOLID_BOUNCES)
        cycles.blur_glossy = 0.0


def furnace_stage(scene, furnace, columns, rows):
    """Make `scene` the furnace (white world, render settings, camera) for a
    grid of `columns` x `rows` cells, without spheres."""
    scene.world = furnace_world()  # before the settings: EEVEE's are partly the world's
    furnace_render_settings(scene, furnace, columns, rows)
    camera = furnace_camera(columns, furnace.get("solid", False), furnace_unit(furnace))
    scene.collection.objects.link(camera)
    scene.camera = camera


def furnace_cell_location(index, columns, rows, solid, unit):
    """Where sphere `index` sits: its grid cell (row-major, row 0 at the top of
    the image), and in a solid furnace its depth level behind it."""
    across = (index % columns + 0.5 - 0.5 * columns) * unit
    up = (0.5 * rows - index // columns - 0.5) * unit
    if not solid:
        return (across, up, 0.0)
    return (across, FURNACE_SOLID_SPACING * (index % FURNACE_SOLID_LEVELS) * unit, up)


def furnace_place_materials(scene, furnace, materials, columns, rows):
    """One sphere per material, in grid order, linked to the scene's master
    collection: domes seen by camera rays only, or in a solid furnace closed UV
    spheres seen by every ray. Returns the objects, in the materials' order."""
    unit = furnace_unit(furnace)
    radius = 0.5 * furnace["radius_fraction"] * unit
    solid = furnace.get("solid", False)
    mesh = (sphere_mesh("Gloffuse furnace solid sphere", radius, FURNACE_SPHERE_SEGMENTS,
                        FURNACE_SPHERE_RINGS, uv_map=FURNACE_UV_MAP)
            if solid else furnace_sphere_mesh(radius))
    objects = []
    for index, material in enumerate(materials):
        obj = bpy.data.objects.new("Furnace sphere %03d" % index, mesh)
        obj.location = furnace_cell_location(index, columns, rows, solid, unit)
        scene.collection.objects.link(obj)
        slot = obj.material_slots[0]
        slot.link = "OBJECT"
        slot.material = material
        if not solid:
            compat_camera_rays_only(obj)
        objects.append(obj)
    return objects


def furnace_scene(furnace):
    """Build the furnace grid in the current (empty) scene and return it."""
    scene = bpy.context.scene
    columns, rows = furnace_grid(furnace)
    furnace_stage(scene, furnace, columns, rows)
    materials = [furnace_material(index, sphere, furnace["color"])
                 for index, sphere in enumerate(furnace["spheres"])]
    furnace_place_materials(scene, furnace, materials, columns, rows)
    return scene


def _log_render_status(stats=None, *_):
    # bpy (Blender as a module) logs no render status, but hands this handler
    # the line Blender's own binary prints ("Remaining: … | Sample 1/64"), which
    # gloffuse reads from the log to follow the render. Blender 3.4's binary
    # passes no text here (it prints the line itself).
    if isinstance(stats, str):
        print("gloffuse render: " + stats, flush=True)


def render_sweep(output):
    """Render the current scene once and save it to `output`; returns render seconds."""
    directory = os.path.dirname(output)
    if directory:
        os.makedirs(directory, exist_ok=True)
    start = time.perf_counter()
    bpy.app.handlers.render_stats.append(_log_render_status)
    try:
        bpy.ops.render.render(write_still=False)
    finally:
        bpy.app.handlers.render_stats.remove(_log_render_status)
    seconds = time.perf_counter() - start
    # save_render writes the scene's image settings; for OpenEXR that is the
    # scene-linear result whatever the view transform.
    # (No scene= argument: in 3.4 passing it leaks an image-format copy and
    # prints "Error: Not freed memory blocks" at exit.)
    render_result_image().save_render(filepath=output)
    if not os.path.isfile(output):
        raise RuntimeError("Blender did not write %s" % output)
    return seconds
