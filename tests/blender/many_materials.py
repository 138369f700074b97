"""A compressed .blend of many materials for `gloffuse audit` (far more than the 256 KiB a
zstd frame of Blender's holds), made in real Blender independently of gloffuse's package.

    blender -b --factory-startup -noaudio --python-exit-code 1 --python many_materials.py -- \
        --out FILE.blend --count N
    python3 many_materials.py --out FILE.blend --count N   (bpy module)

Material k is a white single-scatter GGX Glossy at r=1 (it loses: ~40 %, as the audit
library's glossy-ggx-r1) for even k, a white Diffuse (ok: 100 %) for odd k, all on one mesh.
The file is saved compressed, opened again, and FILE.json written with what Blender itself
lists: {"materials": len(bpy.data.materials)}.
"""
import argparse
import json
import os
import sys
import traceback

import bpy


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", required=True)
    parser.add_argument("--count", type=int, required=True)
    return parser.parse_args(argv)


def make(count):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.filepaths.save_version = 0
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.blur_glossy = 0.0
    mesh = bpy.data.meshes.new("Swatches")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    scene.collection.objects.link(bpy.data.objects.new("Swatches", mesh))
    for k in range(count):
        material = bpy.data.materials.new("material-%05d" % k)
        material.use_nodes = True
        nodes = material.node_tree.nodes
        nodes.clear()
        output = nodes.new("ShaderNodeOutputMaterial")
        output.target = "ALL"
        if k % 2 == 0:
            bsdf = nodes.new("ShaderNodeBsdfGlossy")
            bsdf.distribution = "GGX"
            bsdf.inputs["Roughness"].default_value = 1.0
        else:
            bsdf = nodes.new("ShaderNodeBsdfDiffuse")
        bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        material.node_tree.links.new(bsdf.outputs[0], output.inputs["Surface"])
        mesh.materials.append(material)


def main():
    options = args()
    try:
        out = os.path.abspath(options.out)
        make(options.count)
        bpy.ops.wm.save_as_mainfile(filepath=out, compress=True, relative_remap=False)
        bpy.ops.wm.open_mainfile(filepath=out, load_ui=False)
        with open(os.path.splitext(out)[0] + ".json", "w", encoding="utf-8") as f:
            json.dump({"materials": len(bpy.data.materials)}, f)
    except Exception:
        traceback.print_exc()
        sys.stdout.flush()
        sys.exit(1)
    sys.stdout.flush()


main()
