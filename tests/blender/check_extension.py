"""Checks a gloffuse extension (.zip) in real Blender 4.2+ (the bpy module):

    python3 check_extension.py --zip gloffuse.zip --groups GROUPS.json \
        --user-resources EMPTY_DIR --out RESULT.json

GROUPS.json: the names of the groups the extension must bring (gloffuse's own
summary of what it generated).

  1. Blender's validator (`blender_ext.py validate`, shipped with Blender, with
     Blender's list of tags) accepts the archive;
  2. it installs and enables headless (`bpy.ops.extensions.package_install_files`
     into the "user_default" repository), in a fresh user-resources folder so
     nothing of this machine's Blender set-up is touched;
  3. enabling registers exactly one asset library, in the extension's user
     directory, holding the .blend and its catalog file; the groups load from it
     as assets and each one's catalog is a line of that catalog file;
  4. disabling and enabling again keeps one library; disabling removes it.
Writes RESULT.json (what it saw, and "failures") and exits 1 on any failure.
"""
import argparse
import json
import os
import subprocess
import sys
import traceback


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", required=True)
    parser.add_argument("--groups", required=True)
    parser.add_argument("--user-resources", required=True)
    parser.add_argument("--out", required=True)
    return parser.parse_args(argv)


OPTIONS = args()
# Before bpy starts: every user path (preferences, extensions) under this folder.
os.environ["BLENDER_USER_RESOURCES"] = OPTIONS.user_resources

import bpy  # noqa: E402 -- after the environment it reads at start-up

MODULE = "bl_ext.user_default.gloffuse"


def validate(zip_path):
    scripts = os.path.join(bpy.utils.resource_path("LOCAL"), "scripts")
    validator = os.path.join(scripts, "addons_core", "bl_pkg", "cli", "blender_ext.py")
    tags = os.path.join(scripts, "modules", "_bpy_internal", "extensions", "tags.py")
    run = subprocess.run([sys.executable, validator, "validate", "--valid-tags", tags, zip_path],
                         capture_output=True, text=True)
    return run.returncode, (run.stdout + run.stderr).strip()


def gloffuse_libraries():
    return [library for library in bpy.context.preferences.filepaths.asset_libraries
            if library.name.startswith("Gloffuse")]


def catalogs_in(directory):
    ids = set()
    with open(os.path.join(directory, "blender_assets.cats.txt"), encoding="utf-8") as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith(("#", "VERSION")):
                ids.add(line.split(":")[0])
    return ids


def check(options, seen):
    failures = []
    code, text = validate(options.zip)
    seen["validate"] = {"exit": code, "output": text}
    if code != 0:
        failures.append("Blender's validator refuses the archive: %s" % text)

    result = bpy.ops.extensions.package_install_files(
        filepath=os.path.abspath(options.zip), repo="user_default", enable_on_install=True)
    seen["install"] = sorted(result)
    if MODULE not in bpy.context.preferences.addons:
        failures.append("installing did not enable %s (%s)" % (MODULE, result))
        return failures

    libraries = gloffuse_libraries()
    seen["libraries"] = [(library.name, library.path) for library in libraries]
    if len(libraries) != 1:
        return failures + ["enabling registered %d Gloffuse libraries" % len(libraries)]
    directory = bpy.path.abspath(libraries[0].path)
    expected_dir = bpy.utils.extension_path_user(MODULE, path="library", create=False)
    if os.path.realpath(directory) != os.path.realpath(expected_dir):
        failures.append("the library is at %s, not in the extension's user directory %s"
                        % (directory, expected_dir))
    blends = sorted(n for n in os.listdir(directory) if n.endswith(".blend"))
    seen["library_files"] = sorted(os.listdir(directory))
    if blends != ["gloffuse.blend"]:
        return failures + ["the library folder holds %s" % seen["library_files"]]

    with open(options.groups, encoding="utf-8") as f:
        expected = sorted(json.load(f))
    with bpy.data.libraries.load(os.path.join(directory, blends[0]), assets_only=True) as (src, dst):
        available = sorted(src.node_groups)
        dst.node_groups = list(src.node_groups)
    seen["assets"] = available
    if available != expected:
        failures.append("the library's assets %s are not the generated groups %s"
                        % (available, expected))
    catalogs = catalogs_in(directory)
    for tree in dst.node_groups:
        if tree is None or tree.asset_data is None:
            failures.append("a group of the library is no asset")
        elif tree.asset_data.catalog_id not in catalogs:
            failures.append("%s: catalog %s is not in the library's catalog file"
                            % (tree.name, tree.asset_data.catalog_id))

    bpy.ops.preferences.addon_disable(module=MODULE)
    bpy.ops.preferences.addon_enable(module=MODULE)
    if len(gloffuse_libraries()) != 1:
        failures.append("enabling again left %d Gloffuse libraries" % len(gloffuse_libraries()))
    bpy.ops.preferences.addon_disable(module=MODULE)
    left = [(library.name, library.path) for library in gloffuse_libraries()]
    if left:
        failures.append("disabling left the library registered: %s" % left)
    return failures


def main():
    seen = {"blender_version": bpy.app.version_string}
    try:
        failures = check(OPTIONS, seen)
    except Exception:  # report, do not hide: the test prints the result
        failures = [traceback.format_exc()]
    seen["failures"] = failures
    with open(OPTIONS.out, "w", encoding="utf-8") as f:
        json.dump(seen, f, indent=1)
    for failure in failures:
        print("FAIL:", failure)
    sys.exit(1 if failures else 0)


main()
