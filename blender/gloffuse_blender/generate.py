# ---------------------------------------------------------------------------
# gloffuse generate: add or update the node groups in a Blender file.
#
#   In Blender's Text Editor (no arguments): updates the groups in the open
#   file, touches nothing else, does not save.
#   blender -b --factory-startup -noaudio --python-exit-code 1 --python THIS.py -- [--open IN.blend] [--save OUT.blend]
#   python3 THIS.py [--open IN.blend] [--save OUT.blend]      (with the bpy module)
#
# Prints one line on stdout: GLOFFUSE_RESULT {"blender_version": ..., "groups": [...],
# "renamed": [[yours, now], ...], "saved": ...}, or {"refused": why, ...} when
# --replace-library names a file that is not a gloffuse library (nothing saved).
# The job module of the generate script: the gloffuse binary bundles it with
# the modules it imports, after the header that defines GLOFFUSE_PARAMS (the
# parameter document as a JSON string), and ends the script with
# main(GLOFFUSE_PARAMS).
# ---------------------------------------------------------------------------
import sys
import tempfile

import bpy

from .compat import blender_version_string
from .groups import build_all, group_names, library_contents, mark_library
from .nodes import set_aside_untagged
from .params import load_params
from .previews import preview_groups, render_previews
from .runtime import (
    ScriptArgumentParser,
    log_step,
    open_blend,
    parse_script_args,
    result_line,
    run_main,
    save_blend,
)


def parse_generate_args(argv=None):
    parser = ScriptArgumentParser(
        prog="gloffuse-generate",
        description="Add or update gloffuse's brightness-correction node groups.")
    parser.add_argument("--open", metavar="IN.blend",
                        help="open this .blend file first (default: the file already open)")
    parser.add_argument("--save", metavar="OUT.blend",
                        help="save the result as this .blend file (default: do not save)")
    parser.add_argument("--compress", action="store_true",
                        help="save compressed (as the file opened was)")
    parser.add_argument("--replace-library", metavar="OLD.blend",
                        help="the library the new one replaces: refuse (save nothing) unless "
                             "it carries the gloffuse library marker")
    return parse_script_args(parser, argv)


class _Steps:
    """The generate job's steps, told to gloffuse as each begins (log_step)."""

    def __init__(self, total):
        self.total = total
        self.done = 0

    def next(self, what):
        log_step(self.done, self.total, what)
        self.done += 1


def generate_main(document_text):
    options = parse_generate_args()
    params = load_params(document_text)
    if options.replace_library:
        open_blend(options.replace_library)
        refused = library_contents()
        if refused is not None:
            print(result_line("generate_result", {"blender_version": blender_version_string(),
                               "refused": refused, "saved": None}))
            sys.stdout.flush()
            return
    new_library = not options.open and options.save and bpy.app.background
    if options.open:
        open_blend(options.open)
    elif new_library:
        # A new library file holds the groups and nothing else: not the startup
        # file's cube, camera and light.
        bpy.ops.wm.read_factory_settings(use_empty=True)
    renamed = set_aside_untagged(group_names(params))
    specs = params["groups"]
    previews = bool(params.get("previews")) and bpy.app.background
    steps = _Steps(len(specs) + (sum(len(preview_groups(s)) for s in specs) if previews else 0)
                   + (1 if options.save else 0))
    built = build_all(params, on_spec=lambda spec: steps.next(
        "building %s and its groups" % spec["shader_group"]))
    if new_library:
        mark_library(params)
    if previews:
        with tempfile.TemporaryDirectory(prefix="gloffuse-previews-") as directory:
            render_previews(built, directory, on_preview=lambda name: steps.next(
                "rendering the preview of %s" % name))
    if options.save:
        steps.next("saving the .blend")
    saved = save_blend(options.save, options.compress) if options.save else None
    names = []
    for _spec, trees in built:
        names.extend(tree.name for tree in trees)
    print(result_line("generate_result", {
        "blender_version": blender_version_string(),
        "groups": names,
        "renamed": renamed,
        "saved": saved,
    }))
    sys.stdout.flush()


def main(document_text):
    """The generate job on the parameter document `document_text` (JSON), with
    run_main's error handling: traceback, and exit 1 headless."""
    run_main(lambda: generate_main(document_text))
