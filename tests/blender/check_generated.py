"""End-to-end check of a .blend made by a gloffuse generate script, inside real Blender.

    blender -b --factory-startup -noaudio --python-exit-code 1 --python check_generated.py -- \
        --blend FILE.blend --expect EXPECT.json --out RESULT.json [--generator GEN.py]
    python3 check_generated.py --blend FILE.blend --expect EXPECT.json --out RESULT.json   (bpy module)

EXPECT.json: {"groups": [{"correction_group", "shader_group", "distribution",
              "probe": [[roughness, expected_gain], ...], "description"?: text}]}

Checks, in this order:
  1. structure: the groups exist under their exact names, with the public
     sockets (names, types, order, defaults, min/max, hidden Normal value), asset
     marks and descriptions where the version supports them, the Glossy node's
     distribution, a labelled frame, no overlapping nodes, no ".001" groups;
  2. Gain through Cycles: one render of emission planes whose Strength is the
     correction group's Gain (and, on a second row per group, whose Color is the
     correction Color output for input (0.5, 0.25, 1)), read back from EXR;
  3. the shader group under a white world against a plain Glossy BSDF of the
     same distribution, rendered with the same seed: the ratio must be the gain,
     which also proves that an unconnected group Normal means the shading normal;
  4. with --generator GEN.py: re-running the generate script (in this process,
     as from the Text Editor, and as a separate Blender run with --open/--save)
     keeps the same datablocks, the links of a material using the shader group,
     and adds no ".001" groups.
Writes RESULT.json (everything measured, and "failures") and exits 1 on any failure.
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import traceback

import bpy

# Emission on a camera ray is exact in Cycles; what is left is float32
# arithmetic in the node evaluation (about 1e-7 relative), so 1e-4 is generous.
GAIN_RTOL = 1e-4
# The shader group and the plain Glossy node trace the same paths with the same
# random numbers (same seed, same pixels, no Russian roulette at the first hit,
# no light-threshold roulette, no sample clamping), so their ratio is the gain up to float32 rounding.
BSDF_RTOL = 1e-4
# A plain Glossy plane at normal incidence under a white world reflects E(1, r):
# between about 0.14 (Ashikhmin-Shirley, r = 1) and 1.
GLOSSY_ALBEDO_RANGE = (0.05, 1.05)
INPUT_COLOR = (0.5, 0.25, 1.0)
CELL = 8  # pixels per plane side

CORRECTION_INPUTS = [
    {"name": "Roughness", "type": "VALUE", "default": 0.5, "min": 0.0, "max": 1.0},
    {"name": "Color", "type": "RGBA", "default": (1.0, 1.0, 1.0, 1.0)},
]
CORRECTION_OUTPUTS = [{"name": "Color", "type": "RGBA"}, {"name": "Gain", "type": "VALUE"}]
SHADER_INPUTS = [
    {"name": "Color", "type": "RGBA", "default": (1.0, 1.0, 1.0, 1.0)},
    {"name": "Roughness", "type": "VALUE", "default": 0.5, "min": 0.0, "max": 1.0},
    {"name": "Normal", "type": "VECTOR", "hide_value": True},
]
SHADER_OUTPUTS = [{"name": "BSDF", "type": "SHADER"}]
COPY_SUFFIX = re.compile(r"\.\d{3}$")


# ---------------------------------------------------------------- helpers

def script_args():
    argv = sys.argv
    if "--" in argv:
        return argv[argv.index("--") + 1:]
    return [] if bpy.app.binary_path else argv[1:]


class Report:
    def __init__(self):
        self.failures = []
        self.data = {"blender_version": ".".join(str(v) for v in bpy.app.version)}

    def check(self, ok, message):
        if not ok:
            self.failures.append(message)
        return ok


def close(a, b, rtol, atol=1e-6):
    return math.isfinite(a) and abs(a - b) <= atol + rtol * abs(b)


def interface_sockets(tree, in_out):
    if hasattr(tree, "interface"):
        return [i for i in tree.interface.items_tree
                if i.item_type == "SOCKET" and i.in_out == in_out]
    return list(tree.inputs if in_out == "INPUT" else tree.outputs)


def ensure_node_tree(idblock):
    """Material/world node tree: 5.0 creates it with the datablock and
    deprecates use_nodes; before 5.0 use_nodes creates it."""
    if idblock.node_tree is None and hasattr(idblock, "use_nodes"):
        idblock.use_nodes = True
    return idblock.node_tree


def local_group(name):
    for tree in bpy.data.node_groups:
        if tree.name == name and tree.library is None:
            return tree
    return None


def as_tuple(value):
    try:
        return tuple(float(v) for v in value)
    except TypeError:
        return (float(value),)


# -------------------------------------------------------------- structure

def instance_sockets(tree):
    """Sockets of a group node using `tree`: uniform types ('VALUE', 'RGBA',
    ...) and instance defaults in every version."""
    tmp = bpy.data.node_groups.new("gloffuse check tmp", "ShaderNodeTree")
    try:
        node = tmp.nodes.new("ShaderNodeGroup")
        node.node_tree = tree
        inputs = [(s.name, s.type, as_tuple(s.default_value) if hasattr(s, "default_value") else None)
                  for s in node.inputs]
        outputs = [(s.name, s.type) for s in node.outputs]
    finally:
        bpy.data.node_groups.remove(tmp)
    return inputs, outputs


def check_sockets(report, tree, want_in, want_out):
    where = tree.name
    got_in, got_out = instance_sockets(tree)
    report.check([(n, t) for n, t, _ in got_in] == [(w["name"], w["type"]) for w in want_in],
                 "%s: inputs are %s, expected %s" % (where, [(n, t) for n, t, _ in got_in],
                                                      [(w["name"], w["type"]) for w in want_in]))
    report.check(got_out == [(w["name"], w["type"]) for w in want_out],
                 "%s: outputs are %s, expected %s" % (where, got_out,
                                                       [(w["name"], w["type"]) for w in want_out]))
    iface = interface_sockets(tree, "INPUT")
    for want, sock, inst in zip(want_in, iface, got_in):
        label = "%s: input %s" % (where, want["name"])
        if "default" in want:
            got = as_tuple(sock.default_value)
            report.check(len(got) == len(as_tuple(want["default"])) and all(
                close(g, w, 1e-6) for g, w in zip(got, as_tuple(want["default"]))),
                "%s default is %s, expected %s" % (label, got, want["default"]))
            report.check(inst[2] is not None and all(
                close(g, w, 1e-6) for g, w in zip(inst[2], as_tuple(want["default"]))),
                "%s: a new group node gets %s, expected %s" % (label, inst[2], want["default"]))
        for key, attr in (("min", "min_value"), ("max", "max_value")):
            if key in want:
                report.check(close(getattr(sock, attr), want[key], 1e-6),
                             "%s %s is %s, expected %s" % (label, attr, getattr(sock, attr), want[key]))
        if "hide_value" in want:
            report.check(bool(sock.hide_value) == want["hide_value"],
                         "%s hide_value is %s" % (label, sock.hide_value))
    return {"inputs": [[n, t] for n, t, _ in got_in], "outputs": [list(o) for o in got_out]}


def node_rect(node):
    """(x0, y0, x1, y1) with an estimated height (node.dimensions is zero
    until the node editor draws it)."""
    x, y = node.location
    parent = node.parent
    if not hasattr(node, "location_absolute"):
        while parent is not None:
            x, y = x + parent.location[0], y + parent.location[1]
            parent = parent.parent
    else:
        x, y = node.location_absolute
    rows = sum(1 for s in node.outputs if s.enabled and not s.hide) + \
        sum(1 for s in node.inputs if s.enabled and not s.hide)
    props = 2 if node.bl_idname in ("ShaderNodeMath", "ShaderNodeClamp") else \
        3 if node.bl_idname in ("ShaderNodeMix", "ShaderNodeMixRGB") else 1
    height = 36 + 22 * rows + 24 * props
    return (x, y - height, x + node.width, y)


def check_layout(report, tree):
    nodes = [n for n in tree.nodes if n.bl_idname != "NodeFrame"]
    rects = [(n.name, node_rect(n)) for n in nodes]
    for i in range(len(rects)):
        for j in range(i + 1, len(rects)):
            (na, a), (nb, b) = rects[i], rects[j]
            overlap = a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]
            report.check(not overlap, "%s: nodes %r and %r overlap" % (tree.name, na, nb))


def check_descriptions(report, tree, expected_text):
    info = {}
    if hasattr(tree, "description"):
        info["description"] = tree.description
        report.check(bool(tree.description.strip()), "%s: empty description" % tree.name)
        if expected_text:
            report.check(expected_text.strip() in tree.description,
                         "%s: description does not contain the spec's text" % tree.name)
    if hasattr(tree, "asset_mark"):
        data = tree.asset_data
        info["asset"] = data is not None
        if report.check(data is not None, "%s: not marked as an asset" % tree.name):
            report.check(bool(data.description.strip()), "%s: asset has no description" % tree.name)
            if expected_text:
                report.check(expected_text.strip() in data.description,
                             "%s: asset description does not contain the spec's text" % tree.name)
    return info


def check_structure(report, expect):
    out = []
    copies = [t.name for t in bpy.data.node_groups if COPY_SUFFIX.search(t.name)]
    report.check(not copies, "node groups with copy suffixes: %s" % copies)
    for spec in expect["groups"]:
        entry = {"correction_group": spec["correction_group"], "shader_group": spec["shader_group"]}
        out.append(entry)
        corr = local_group(spec["correction_group"])
        shader = local_group(spec["shader_group"])
        if not report.check(corr is not None, "missing group %r" % spec["correction_group"]):
            continue
        if not report.check(shader is not None, "missing group %r" % spec["shader_group"]):
            continue
        for tree in (corr, shader):
            report.check(tree.bl_idname == "ShaderNodeTree", "%s is a %s" % (tree.name, tree.bl_idname))
        entry["correction_sockets"] = check_sockets(report, corr, CORRECTION_INPUTS, CORRECTION_OUTPUTS)
        entry["shader_sockets"] = check_sockets(report, shader, SHADER_INPUTS, SHADER_OUTPUTS)
        entry["correction_info"] = check_descriptions(report, corr, spec.get("description"))
        entry["shader_info"] = check_descriptions(report, shader, spec.get("description"))

        frames = [n for n in corr.nodes if n.bl_idname == "NodeFrame"]
        children = [n for n in corr.nodes if n.parent is not None]
        report.check(len(frames) == 1 and frames[0].label and children,
                     "%s: expected one labelled frame holding the computation" % corr.name)
        maths = [n for n in corr.nodes if n.bl_idname == "ShaderNodeMath"]
        report.check(all(n.label for n in maths), "%s: a Math node has no label" % corr.name)
        entry["correction_labels"] = [n.label for n in corr.nodes if n.label]
        check_layout(report, corr)
        check_layout(report, shader)

        glossies = [n for n in shader.nodes
                    if n.bl_idname in ("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic")]
        if report.check(len(glossies) == 1, "%s: %d Glossy nodes" % (shader.name, len(glossies))):
            glossy = glossies[0]
            entry["glossy_distribution"] = glossy.distribution
            report.check(glossy.distribution == spec["distribution"],
                         "%s: Glossy distribution %s, expected %s"
                         % (shader.name, glossy.distribution, spec["distribution"]))
            normal = glossy.inputs["Normal"]
            report.check(normal.is_linked and normal.links[0].from_node.bl_idname == "NodeGroupInput"
                         and normal.links[0].from_socket.name == "Normal",
                         "%s: Glossy Normal is not fed by the group's Normal" % shader.name)
            color = glossy.inputs["Color"]
            report.check(color.is_linked and getattr(color.links[0].from_node, "node_tree", None) == corr,
                         "%s: Glossy Color is not fed by %s" % (shader.name, corr.name))
        users = [n for n in shader.nodes if n.bl_idname == "ShaderNodeGroup"]
        report.check(len(users) == 1 and users[0].node_tree == corr,
                     "%s: expected one group node using %s" % (shader.name, corr.name))
    return out


# ---------------------------------------------------------------- renders

def new_plane(name, x, y, material, collection, warped=False):
    """A square plane facing +Z (the camera) centred in its cell, with a gap to
    its neighbours and visible to camera rays only, so no reflected ray can hit
    another plane (that would couple the planes' random paths). A warped plane
    has one corner raised and smooth shading, so its shading normal differs
    from its geometric normal almost everywhere."""
    mesh = bpy.data.meshes.new(name)
    h = 0.4
    lift = 0.3 if warped else 0.0
    mesh.from_pydata([(x - h, y - h, 0), (x + h, y - h, 0), (x + h, y + h, lift), (x - h, y + h, 0)],
                     [], [(0, 1, 2, 3)])
    for polygon in mesh.polygons:
        polygon.use_smooth = warped
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    for ray in ("diffuse", "glossy", "transmission", "volume_scatter", "shadow"):
        if hasattr(obj, "visible_" + ray):
            setattr(obj, "visible_" + ray, False)
    collection.objects.link(obj)
    return obj


def render_scene(cols, rows, world_strength, samples):
    scene = bpy.data.scenes.new("gloffuse check")
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 1.0
    scene.cycles.seed = 7
    # No clamping: light reached after one bounce counts as "indirect" and the
    # default indirect clamp (10) would cut the brightened samples only.
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    # No light-sampling threshold: its Russian roulette on shadow rays depends
    # on the BSDF's value, so it would draw different paths for a brighter BSDF.
    scene.cycles.light_sampling_threshold = 0.0
    scene.render.resolution_x = CELL * cols
    scene.render.resolution_y = CELL * rows
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "IMAGE"
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGBA"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"

    world = bpy.data.worlds.new("gloffuse check world")
    tree = ensure_node_tree(world)
    background = [n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground"][0]
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = world_strength
    scene.world = world

    cam_data = bpy.data.cameras.new("gloffuse check camera")
    cam_data.type = "ORTHO"
    cam_data.sensor_fit = "HORIZONTAL"
    cam_data.ortho_scale = float(cols)
    cam = bpy.data.objects.new("gloffuse check camera", cam_data)
    cam.location = (0.0, 0.0, 5.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    return scene


def cell_center(row, col, cols, rows):
    return col - (cols - 1) / 2.0, (rows - 1) / 2.0 - row


def render_and_read(scene, path):
    scene.render.filepath = path
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True, scene=scene.name)
    image = bpy.data.images.load(path, check_existing=False)
    try:
        width, height = image.size
        pixels = list(image.pixels[:])
    finally:
        bpy.data.images.remove(image)
    return width, height, pixels


def cell_rgb(pixels, width, rows, row, col):
    """Mean RGB of the 2x2 pixels at the centre of a cell (rows from the top;
    image rows run from the bottom)."""
    total = [0.0, 0.0, 0.0]
    y0 = (rows - 1 - row) * CELL + CELL // 2 - 1
    x0 = col * CELL + CELL // 2 - 1
    for y in (y0, y0 + 1):
        for x in (x0, x0 + 1):
            i = 4 * (y * width + x)
            for c in range(3):
                total[c] += pixels[i + c] / 4.0
    return total


def material_with(name):
    mat = bpy.data.materials.new(name)
    tree = ensure_node_tree(mat)
    tree.nodes.clear()
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    return mat, tree, out


def measure_gain(report, expect, tmpdir):
    """Row 2g: Emission Strength = Gain; row 2g + 1: Emission Color = Color output."""
    groups = [g for g in expect["groups"] if local_group(g["correction_group"])]
    cols = max(len(g["probe"]) for g in groups)
    rows = 2 * len(groups)
    scene = render_scene(cols, rows, 0.0, 1)
    for gi, spec in enumerate(groups):
        corr = local_group(spec["correction_group"])
        for pi, (rough, _gain) in enumerate(spec["probe"]):
            for kind in ("gain", "color"):
                row = 2 * gi + (kind == "color")
                mat, tree, out = material_with("check %s %d %s" % (kind, pi, corr.name))
                group = tree.nodes.new("ShaderNodeGroup")
                group.node_tree = corr
                value = tree.nodes.new("ShaderNodeValue")
                value.outputs[0].default_value = rough
                tree.links.new(value.outputs[0], group.inputs["Roughness"])
                emission = tree.nodes.new("ShaderNodeEmission")
                if kind == "gain":
                    emission.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
                    tree.links.new(group.outputs["Gain"], emission.inputs["Strength"])
                else:
                    group.inputs["Color"].default_value = INPUT_COLOR + (1.0,)
                    tree.links.new(group.outputs["Color"], emission.inputs["Color"])
                    emission.inputs["Strength"].default_value = 1.0
                tree.links.new(emission.outputs[0], out.inputs["Surface"])
                x, y = cell_center(row, pi, cols, rows)
                new_plane("check %s %d %d" % (kind, gi, pi), x, y, mat, scene.collection)
    width, _height, pixels = render_and_read(scene, os.path.join(tmpdir, "gain.exr"))
    results = []
    for gi, spec in enumerate(groups):
        entry = {"correction_group": spec["correction_group"], "gain": [], "color": []}
        for pi, (rough, gain) in enumerate(spec["probe"]):
            got = cell_rgb(pixels, width, rows, 2 * gi, pi)
            entry["gain"].append([rough, gain, got[0]])
            report.check(all(close(g, gain, GAIN_RTOL) for g in got),
                         "%s: Gain at r=%s is %s, expected %.7g"
                         % (spec["correction_group"], rough, got, gain))
            got = cell_rgb(pixels, width, rows, 2 * gi + 1, pi)
            want = [c * gain for c in INPUT_COLOR]
            entry["color"].append([rough, want, got])
            report.check(all(close(g, w, GAIN_RTOL) for g, w in zip(got, want)),
                         "%s: Color at r=%s is %s, expected %s"
                         % (spec["correction_group"], rough, got, want))
        results.append(entry)
    return results


def measure_bsdf(report, expect, tmpdir):
    """Same warped, smooth-shaded planes twice under a white world: the shader
    group (Normal left unconnected) and a plain Glossy node. Ratio = gain, pixel
    for pixel, only if the group's BSDF uses the same (interpolated shading)
    normal as the plain node."""
    groups = [g for g in expect["groups"] if local_group(g["shader_group"])]
    cols = max(len(g["probe"]) for g in groups)
    rows = len(groups)
    scene = render_scene(cols, rows, 1.0, 4)
    slots = []
    for gi, spec in enumerate(groups):
        for pi, (rough, _gain) in enumerate(spec["probe"]):
            mat, tree, out = material_with("check bsdf %d %d" % (gi, pi))
            x, y = cell_center(gi, pi, cols, rows)
            new_plane("check bsdf %d %d" % (gi, pi), x, y, mat, scene.collection, warped=True)
            slots.append((gi, pi, rough, spec, tree, out))

    def fill(variant):
        for gi, pi, rough, spec, tree, out in slots:
            for node in [n for n in tree.nodes if n != out]:
                tree.nodes.remove(node)
            if variant == "group":
                node = tree.nodes.new("ShaderNodeGroup")
                node.node_tree = local_group(spec["shader_group"])
                node.inputs["Roughness"].default_value = rough
            else:
                node = tree.nodes.new("ShaderNodeBsdfGlossy")
                node.distribution = spec["distribution"]
                node.inputs["Roughness"].default_value = rough
                node.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
            tree.links.new(node.outputs[0], out.inputs["Surface"])

    fill("group")
    width, _h, with_group = render_and_read(scene, os.path.join(tmpdir, "bsdf_group.exr"))
    fill("plain")
    _w, _h, plain = render_and_read(scene, os.path.join(tmpdir, "bsdf_plain.exr"))
    results = []
    for gi, pi, rough, spec, _tree, _out in slots:
        gain = spec["probe"][pi][1]
        a = cell_rgb(with_group, width, rows, gi, pi)[1]
        b = cell_rgb(plain, width, rows, gi, pi)[1]
        ratio = a / b if b else float("nan")
        results.append({"shader_group": spec["shader_group"], "roughness": rough,
                        "plain_glossy": b, "shader_group_value": a, "ratio": ratio,
                        "expected_ratio": gain})
        lo, hi = GLOSSY_ALBEDO_RANGE
        report.check(lo <= b <= hi, "%s: plain Glossy at r=%s renders %s, outside %s"
                     % (spec["shader_group"], rough, b, GLOSSY_ALBEDO_RANGE))
        report.check(close(ratio, gain, BSDF_RTOL),
                     "%s: at r=%s the group renders %s = %s x plain Glossy, expected x %.6g "
                     "(an unconnected Normal must mean the shading normal)"
                     % (spec["shader_group"], rough, a, ratio, gain))
    return results


# ------------------------------------------------------------------ re-run

def make_user_materials(expect):
    """One material per shader group, linked like an artist would do it."""
    made = []
    for spec in expect["groups"]:
        shader = local_group(spec["shader_group"])
        if shader is None:
            continue
        mat, tree, out = material_with("gloffuse check uses %s" % spec["shader_group"])
        mat.use_fake_user = True
        group = tree.nodes.new("ShaderNodeGroup")
        group.name = "gloffuse"
        group.node_tree = shader
        rgb = tree.nodes.new("ShaderNodeRGB")
        rgb.outputs[0].default_value = INPUT_COLOR + (1.0,)
        value = tree.nodes.new("ShaderNodeValue")
        value.outputs[0].default_value = 0.3
        geometry = tree.nodes.new("ShaderNodeNewGeometry")
        tree.links.new(rgb.outputs[0], group.inputs["Color"])
        tree.links.new(value.outputs[0], group.inputs["Roughness"])
        tree.links.new(geometry.outputs["Normal"], group.inputs["Normal"])
        tree.links.new(group.outputs["BSDF"], out.inputs["Surface"])
        made.append((mat.name, spec["shader_group"]))
    return made


def check_user_materials(report, made, stage):
    for mat_name, group_name in made:
        mat = bpy.data.materials.get(mat_name)
        if not report.check(mat is not None, "%s: material %r is gone" % (stage, mat_name)):
            continue
        node = mat.node_tree.nodes.get("gloffuse")
        tree = getattr(node, "node_tree", None)
        report.check(tree is not None and tree.name == group_name,
                     "%s: material %r uses %r, expected %r"
                     % (stage, mat_name, tree and tree.name, group_name))
        if node is not None:
            for socket in ("Color", "Roughness", "Normal"):
                report.check(node.inputs[socket].is_linked,
                             "%s: material %r lost its link into %s" % (stage, mat_name, socket))
            report.check(node.outputs["BSDF"].is_linked,
                         "%s: material %r lost its BSDF link" % (stage, mat_name))


def group_pointers(expect):
    out = {}
    for spec in expect["groups"]:
        for key in ("correction_group", "shader_group"):
            tree = local_group(spec[key])
            if tree is not None:
                out[spec[key]] = tree.as_pointer()
    return out


def rerun_in_process(report, expect, generator, made):
    """Run the generate script as the Text Editor would: no arguments."""
    before = group_pointers(expect)
    count = len(bpy.data.node_groups)
    with open(generator, encoding="utf-8") as handle:
        code = compile(handle.read(), generator, "exec")
    saved_argv = sys.argv
    sys.argv = [saved_argv[0]]
    try:
        exec(code, {"__name__": "__main__", "__file__": generator})
    except BaseException as error:  # the script exits 1 on errors when headless
        report.check(False, "in-process re-run failed: %r" % (error,))
    finally:
        sys.argv = saved_argv
    after = group_pointers(expect)
    report.check(before == after, "in-process re-run changed datablocks: %s -> %s" % (before, after))
    report.check(len(bpy.data.node_groups) == count,
                 "in-process re-run changed the number of node groups: %d -> %d"
                 % (count, len(bpy.data.node_groups)))
    check_user_materials(report, made, "in-process re-run")
    check_structure(report, expect)
    return {"same_pointers": before == after, "groups": count}


def generator_command(generator, args):
    if bpy.app.binary_path:
        return [bpy.app.binary_path, "-b", "--factory-startup", "-noaudio",
                "--python-exit-code", "1", "--python", generator, "--"] + args
    return [sys.executable, generator] + args


def run_generator(report, generator, args, stage):
    command = generator_command(generator, args)
    proc = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=300)
    lines = [l for l in proc.stdout.splitlines() if l.startswith("GLOFFUSE_RESULT ")]
    info = {"command": command, "returncode": proc.returncode}
    ok = report.check(proc.returncode == 0 and len(lines) == 1,
                      "%s: %s exited %d with %d result lines; stderr: %s"
                      % (stage, " ".join(command), proc.returncode, len(lines), proc.stderr[-2000:]))
    if ok:
        info["result"] = json.loads(lines[0][len("GLOFFUSE_RESULT "):])
    return info


def rerun_subprocess(report, expect, generator, made, tmpdir):
    """Save this file (with the user materials), regenerate it from a separate
    Blender run with --open/--save, then with --save over the same file, and
    open the result."""
    first = os.path.join(tmpdir, "rerun_in.blend")
    second = os.path.join(tmpdir, "rerun_out.blend")
    for path in (first, first + "1", second, second + "1"):
        if os.path.exists(path):
            os.remove(path)
    bpy.ops.wm.save_as_mainfile(filepath=first, check_existing=False, copy=True)
    info = {"new_file": run_generator(report, generator, ["--open", first, "--save", second],
                                      "re-run to a new file")}
    saved = info["new_file"].get("result", {}).get("saved")
    report.check(saved == second, "re-run reported saved=%r, expected %r" % (saved, second))
    info["same_file"] = run_generator(report, generator, ["--open", second, "--save", second],
                                      "re-run over the same file")
    report.check(not os.path.exists(second + "1"),
                 "saving over %s left a backup %s1" % (second, second))
    bpy.ops.wm.open_mainfile(filepath=second)
    check_user_materials(report, made, "separate re-run")
    check_structure(report, expect)
    info["node_groups"] = sorted(t.name for t in bpy.data.node_groups)
    return info


# -------------------------------------------------------------------- main

def parse_args(args):
    parser = argparse.ArgumentParser(prog="check_generated.py")
    parser.add_argument("--blend", required=True)
    parser.add_argument("--expect", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--generator", help="the assembled generate script, to test re-runs")
    parser.add_argument("--tmpdir", help="keep renders and re-run files here")
    parser.add_argument("--skip-render", action="store_true")
    return parser.parse_args(args)


def run(options, report):
    with open(options.expect, encoding="utf-8") as handle:
        expect = json.load(handle)
    tmpdir = options.tmpdir or tempfile.mkdtemp(prefix="gloffuse-check-")
    os.makedirs(tmpdir, exist_ok=True)
    report.data["tmpdir"] = tmpdir
    bpy.ops.wm.open_mainfile(filepath=os.path.abspath(options.blend))
    report.data["structure"] = check_structure(report, expect)
    if not options.skip_render:
        report.data["gain_renders"] = measure_gain(report, expect, tmpdir)
        report.data["bsdf_renders"] = measure_bsdf(report, expect, tmpdir)
    if options.generator:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(options.blend))
        made = make_user_materials(expect)
        generator = os.path.abspath(options.generator)
        report.data["rerun_in_process"] = rerun_in_process(report, expect, generator, made)
        report.data["rerun_subprocess"] = rerun_subprocess(report, expect, generator, made, tmpdir)


def main():
    options = parse_args(script_args())
    report = Report()
    try:
        run(options, report)
    except Exception:
        report.failures.append("checker crashed:\n" + traceback.format_exc())
    report.data["failures"] = report.failures
    report.data["passed"] = not report.failures
    with open(options.out, "w", encoding="utf-8") as handle:
        json.dump(report.data, handle, ensure_ascii=False, indent=1)
    for failure in report.failures:
        sys.stderr.write("FAIL: %s\n" % failure)
    print("CHECK %s: %d failures (%s)" % ("PASSED" if not report.failures else "FAILED",
                                         len(report.failures), options.out))
    sys.stdout.flush()
    sys.stderr.flush()
    if report.failures:
        sys.exit(1)


if __name__ == "__main__":
    main()
