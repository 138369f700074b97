# ---------------------------------------------------------------------------
# gloffuse generate: add or update the node groups in a Blender file.
#
#   In Blender's Text Editor (no arguments): updates the groups in the open
#   file, touches nothing else, does not save.
#   blender -b --factory-startup -noaudio --python-exit-code 1 --python THIS.py -- [--open IN.blend] [--save OUT.blend]
#   python3 THIS.py [--open IN.blend] [--save OUT.blend]      (with the bpy module)
#
# Prints one line on stdout: GLOFFUSE_RESULT {"blender_version": ..., "groups": [...], "saved": ...}
# Needs GLOFFUSE_PARAMS (header) and, above this file, the library parts compat.py,
# params.py, nodes.py, roughness_groups.py, normal_group.py, view_groups.py,
# layered_groups.py, groups.py and runtime.py, and previews.py.
# ---------------------------------------------------------------------------
import sys  # also imported by runtime.py; repeated so this file reads on its own
import tempfile

import bpy


def parse_generate_args(argv=None):
    parser = ScriptArgumentParser(  # noqa: F821 -- runtime.py
        prog="gloffuse-generate",
        description="Add or update gloffuse's brightness-correction node groups.")
    parser.add_argument("--open", metavar="IN.blend",
                        help="open this .blend file first (default: the file already open)")
    parser.add_argument("--save", metavar="OUT.blend",
                        help="save the result as this .blend file (default: do not save)")
    return parse_script_args(parser, argv)  # noqa: F821 -- runtime.py


def generate_main():
    options = parse_generate_args()
    params = load_params(GLOFFUSE_PARAMS)  # noqa: F821 -- header; params.py
    if options.open:
        open_blend(options.open)  # noqa: F821 -- runtime.py
    elif options.save and bpy.app.background:
        # A new library file holds the groups and nothing else: not the startup
        # file's cube, camera and light.
        bpy.ops.wm.read_factory_settings(use_empty=True)
    built = build_all(params)  # noqa: F821 -- groups.py
    if params.get("previews") and bpy.app.background:
        with tempfile.TemporaryDirectory(prefix="gloffuse-previews-") as directory:
            render_previews(built, directory)  # noqa: F821 -- previews.py
    saved = save_blend(options.save) if options.save else None  # noqa: F821 -- runtime.py
    names = []
    for _spec, trees in built:
        names.extend(tree.name for tree in trees)
    print(result_line({  # noqa: F821 -- runtime.py
        "blender_version": blender_version_string(),  # noqa: F821 -- compat.py
        "groups": names,
        "saved": saved,
    }))
    sys.stdout.flush()


if __name__ == "__main__":
    run_main(generate_main)  # noqa: F821 -- runtime.py: traceback, exit 1 headless
