# ---------------------------------------------------------------------------
# user_blend.py: makes and reads back "a user's own .blend" for tests/user_blend.rs.
#
#   make OUT.blend [--compress] [--texture]   a cube with a material; with
#       --texture, an Image Texture node whose image is the relative path
#       //tex.png (the test puts tex.png beside OUT.blend)
#   inspect IN.blend                          prints one line
#       GLOFFUSE_RESULT {"version": [major, minor, patch], "images": {name: filepath},
#                        "groups": [names], "materials": [names]}
# ---------------------------------------------------------------------------
import argparse
import json
import sys

import bpy


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(prog="user_blend")
    parser.add_argument("action", choices=["make", "inspect"])
    parser.add_argument("path")
    parser.add_argument("--compress", action="store_true")
    parser.add_argument("--texture", action="store_true")
    return parser.parse_args(argv)


def make(path, compress, texture):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add()
    material = bpy.data.materials.new("User Material")
    material.use_nodes = True
    if texture:
        image = bpy.data.images.new("tex", 4, 4)
        image.source = "FILE"
        image.filepath = "//tex.png"
        node = material.node_tree.nodes.new("ShaderNodeTexImage")
        node.image = image
    bpy.context.object.data.materials.append(material)
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=compress, relative_remap=False)


def inspect(path):
    bpy.ops.wm.open_mainfile(filepath=path)
    print("GLOFFUSE_RESULT " + json.dumps({
        "version": list(bpy.data.version),
        "images": {image.name: image.filepath for image in bpy.data.images},
        "groups": sorted(group.name for group in bpy.data.node_groups),
        "materials": sorted(material.name for material in bpy.data.materials),
    }))


def main():
    options = args()
    if options.action == "make":
        make(options.path, options.compress, options.texture)
    else:
        inspect(options.path)
    sys.stdout.flush()


main()
