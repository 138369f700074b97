# ---------------------------------------------------------------------------
# furnace_main.py: the "main" of gloffuse's verify and refresh jobs.
#
# Appended by the gloffuse binary after the header that defines
# GLOFFUSE_PARAMS (the parameter document as a JSON string), the library parts
# and furnace.py. It builds the groups of the document (groups.py), the
# furnace scene (furnace.py), renders it once and prints one line
#   GLOFFUSE_RESULT {json}
# to stdout at the end.
#
#   blender -b --factory-startup -noaudio --python-exit-code 1 --python THIS.py -- [--output OUT.exr]
#   python3 THIS.py [--output OUT.exr]        (with the bpy module)
# The only argument, --output, overrides furnace.output. On any error it
# prints a traceback and exits 1 (runtime.py's run_main).
# ---------------------------------------------------------------------------
import json  # also imported by furnace.py; repeated so this file reads on its own
import os
import sys

import bpy


def furnace_main():
    args = parse_furnace_args(script_args())  # noqa: F821 -- runtime.py
    document = json.loads(GLOFFUSE_PARAMS)  # noqa: F821 -- defined by the generated header
    furnace = furnace_params(document)
    output = os.path.abspath(args.output or furnace["output"])
    if not bpy.app.background:
        raise RuntimeError("the furnace script starts from an empty factory scene, which "
                           "would discard the open file: run it headless (blender -b, or "
                           "python3 with the bpy module)")

    bpy.ops.wm.read_factory_settings(use_empty=True)
    if document.get("groups"):
        # A sweep of plain BSDFs only may come without groups; build_all
        # validates the generate fields (and insists on at least one group).
        build_all(resolve_params(document))  # noqa: F821 -- groups.py, params.py
    scene = furnace_scene(furnace)
    seconds = render_sweep(output)

    result = {
        "blender_version": blender_version_string(),  # noqa: F821 -- compat.py
        "output": output,
        "width": scene.render.resolution_x,
        "height": scene.render.resolution_y,
        "render_seconds": round(seconds, 3),
    }
    print(result_line(result))  # noqa: F821 -- runtime.py
    sys.stdout.flush()


if __name__ == "__main__":
    run_main(furnace_main)  # noqa: F821 -- runtime.py: traceback and exit 1 headless
