# ---------------------------------------------------------------------------
# gloffuse runtime.py: helpers for the jobs' mains (generate.py,
# furnace_job.py): the script's own arguments, opening and saving .blend
# files, the result line, and error handling that never quits an interactive
# Blender.
#
# A module of the gloffuse_blender package; of the others it imports only
# contract.py (the result line's fields).
# Functions and classes only.
#
#   script_args(argv=None) -> the arguments meant for the script
#   ScriptArgumentParser, parse_script_args(parser) -> options (never exits)
#   open_blend(path), save_blend(path, compress) -> absolute path
#   result_line(kind, payload) -> "GLOFFUSE_RESULT {...}", its fields checked
#   shown_path(path) -> the path as UTF-8 text (bad bytes shown as U+FFFD)
#   run_main(main) -> runs main with the error handling described there, and
#       ends the process when main is done (see end_process)
# ---------------------------------------------------------------------------
import argparse
import json
import os
import shutil
import sys
import tempfile
import traceback

import bpy

from .contract import check_fields

def running_in_blender_binary():
    """True inside the blender executable (its Text Editor or --python),
    False when Blender is imported as the `bpy` module."""
    return bool(bpy.app.binary_path)


def script_args(argv=None):
    """The arguments meant for the script: those after "--" if present;
    otherwise none inside the blender binary (Text Editor, or --python
    without "--"), and argv[1:] under a plain Python with the bpy module."""
    argv = list(sys.argv if argv is None else argv)
    if "--" in argv:
        return argv[argv.index("--") + 1:]
    if running_in_blender_binary():
        return []
    return argv[1:]


class ArgumentError(ValueError):
    """Bad command-line arguments for a gloffuse script."""


class ScriptArgumentParser(argparse.ArgumentParser):
    """argparse that raises ArgumentError instead of exiting, so a mistake
    never quits an interactive Blender."""

    def error(self, message):
        raise ArgumentError("%s: %s\n%s" % (self.prog, message, self.format_usage().strip()))


def parse_script_args(parser, argv=None):
    """Parse the script's arguments. Headless: strictly. Interactive (the Text
    Editor of a Blender that may have been started with other arguments after
    "--"): unknown arguments are reported and ignored."""
    args = script_args(argv)
    if bpy.app.background:
        return parser.parse_args(args)
    options, ignored = parser.parse_known_args(args)
    if ignored:
        sys.stderr.write("%s: ignoring arguments %s\n" % (parser.prog, " ".join(ignored)))
    return options


def open_blend(path):
    path = os.path.abspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError("no .blend file at %s" % path)
    bpy.ops.wm.open_mainfile(filepath=path)
    return path


def save_blend(path, compress=False):
    """Save the open file as `path` without a .blend1 backup (the caller
    handles backups and atomic renames), compressed if asked (as the user's
    file was: gloffuse keeps a file's compression)."""
    path = os.path.abspath(path)
    directory = os.path.dirname(path)
    if directory and not os.path.isdir(directory):
        raise FileNotFoundError("the folder %s does not exist" % directory)
    filepaths = bpy.context.preferences.filepaths
    old_versions = filepaths.save_version
    filepaths.save_version = 0
    said = None
    try:
        result = bpy.ops.wm.save_as_mainfile(filepath=path, check_existing=False,
                                             copy=False, compress=compress)
    except RuntimeError as error:
        result, said = (), " ".join(str(error).split())
    finally:
        filepaths.save_version = old_versions
    if said is not None or "FINISHED" not in result or not os.path.isfile(path):
        raise RuntimeError(save_failure(path, compress, said or "the save did not finish"))
    return path


def shown_path(path):
    """`path` as text for the result line: a name that is not UTF-8 (surrogate-escaped in
    Python) shows U+FFFD where its bad bytes are, as JSON can hold no lone surrogate."""
    return os.fsencode(path).decode("utf-8", "replace")


def _size(n):
    return "%.1f MB" % (n / 1e6) if n >= 100e3 else "%d bytes" % n


def saved_size(compress):
    """The bytes the open file takes saved (a copy written to a temporary
    folder and removed), or None when even that fails."""
    with tempfile.TemporaryDirectory(prefix="gloffuse-size-") as directory:
        copy = os.path.join(directory, "size.blend")
        try:
            bpy.ops.wm.save_as_mainfile(filepath=copy, check_existing=False, copy=True,
                                        compress=compress)
            return os.path.getsize(copy)
        except (RuntimeError, OSError):
            return None


def save_failure(path, compress, said):
    """Why saving `path` failed, in words. On a full disk Blender says nothing
    to the point ("Error: Success", or "No such file or directory" for the
    file it could not finish), so the device's free space is compared with
    what the file takes when saved elsewhere."""
    directory = os.path.dirname(path) or "."
    try:
        free = shutil.disk_usage(directory).free
    except OSError:
        return "Blender could not save %s (Blender said: %s)" % (path, said)
    needed = saved_size(compress)
    if needed is not None and needed >= free:
        return ("no space left on the device: saving %s takes about %s, and the device holding "
                "%s has %s free; free some space there or save elsewhere (Blender said: %s)"
                % (path, _size(needed), directory, _size(free), said))
    return ("Blender could not save %s (Blender said: %s); the device holding %s has %s free"
            % (path, said, directory, _size(free)))


def result_line(kind, payload):
    """The one machine-readable line a main prints on stdout; `payload` must hold
    the fields contract.py gives `kind`."""
    check_fields(payload, kind, "the %s" % kind.replace("_", " "))
    return "GLOFFUSE_RESULT " + json.dumps(payload, sort_keys=True)


def log_step(done, total, what):
    """Say on stdout, which gloffuse reads as the job runs, that `done` of
    `total` steps are finished and `what` comes next."""
    print("gloffuse step %d/%d: %s" % (done, total, what), flush=True)


def job_is_the_program():
    """Whether this job is the program itself (python THIS.py), not code that
    another script runs in its own process (exec), whose process is not ours
    to end."""
    this = globals().get("__file__")
    return bool(this) and os.path.abspath(sys.argv[0]) == os.path.abspath(this)


def end_process(code):
    """End a headless job with exit status `code`, its output flushed.

    Under the bpy module, when the job is the program, the process ends at once
    (os._exit): the interpreter's
    normal exit runs Blender's shutdown, which can hang for good (bpy 4.5 with
    a Python-evaluated driver in the open file), and by now the files are
    saved and the result line printed, so nothing is left to do but remove
    Blender's session temp folder, as its shutdown would. The blender binary
    quits by itself once the script returns, cleaning up after itself; an
    error there exits with `code`."""
    sys.stdout.flush()
    sys.stderr.flush()
    if running_in_blender_binary() or not job_is_the_program():
        if code:
            sys.exit(code)
        return
    session = os.path.normpath(bpy.app.tempdir or "")
    if os.path.basename(session).startswith("blender_"):
        shutil.rmtree(session, ignore_errors=True)
    os._exit(code)


def run_main(main):
    """Run main() and end the process (end_process: at once under the bpy
    module). On error print the traceback and, headless, exit 1 (2 for bad
    arguments), because blender -b --python ignores exceptions unless
    --python-exit-code is given. Interactive (Text Editor) the exception is
    re-raised so Blender shows it and keeps running."""
    try:
        main()
    except ArgumentError as error:
        sys.stderr.write("%s\n" % error)
        if bpy.app.background:
            end_process(2)
        raise
    except Exception:
        traceback.print_exc()
        if bpy.app.background:
            end_process(1)
        raise
    if bpy.app.background:
        end_process(0)


def render_result_image():
    """The Render Result image of the last render (furnace.py, previews.py)."""
    for image in bpy.data.images:
        if image.type == "RENDER_RESULT":
            return image
    raise RuntimeError("rendering produced no Render Result image")
