# ---------------------------------------------------------------------------
# gloffuse furnace_job.py: the main of gloffuse's verify and refresh jobs.
#
# The job module of the furnace script: the gloffuse binary bundles it with
# the modules it imports, after the header that defines GLOFFUSE_PARAMS (the
# parameter document as a JSON string), and ends the script with
# main(GLOFFUSE_PARAMS). It builds the groups of the document (groups.py), the
# furnace scene (furnace.py), renders it once and prints one line
#   GLOFFUSE_RESULT {json}
# to stdout at the end.
#
#   blender -b --factory-startup -noaudio --python-exit-code 1 --python THIS.py -- [--output OUT.exr]
#   python3 THIS.py [--output OUT.exr]        (with the bpy module)
# The only argument, --output, overrides furnace.output. On any error it
# prints a traceback and exits 1 (runtime.py's run_main).
# ---------------------------------------------------------------------------
import json
import os
import sys

import bpy

from .compat import blender_version_string
from .furnace import furnace_params, furnace_scene, parse_furnace_args, render_sweep
from .groups import build_all
from .params import resolve_params
from .runtime import result_line, run_main, script_args


def furnace_main(document_text):
    args = parse_furnace_args(script_args())
    document = json.loads(document_text)
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
        build_all(resolve_params(document))
    scene = furnace_scene(furnace)
    seconds = render_sweep(output)

    result = {
        "blender_version": blender_version_string(),
        "output": output,
        "width": scene.render.resolution_x,
        "height": scene.render.resolution_y,
        "render_seconds": round(seconds, 3),
    }
    print(result_line("furnace_result", result))
    sys.stdout.flush()


def main(document_text):
    """The furnace job on the parameter document `document_text` (JSON), with
    run_main's error handling: traceback, and exit 1 headless."""
    run_main(lambda: furnace_main(document_text))
