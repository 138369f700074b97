"""Checks that a library .blend made by `gloffuse generate --blend` is an asset
library an artist can use as it is, inside real Blender.

    blender -b --factory-startup -noaudio --python-exit-code 1 --python check_assets.py -- \
        --blend FILE.blend --out RESULT.json
    python3 check_assets.py --blend FILE.blend --out RESULT.json   (bpy module)

Checks, against the catalog definition file beside the .blend (read as text,
independently of gloffuse):
  1. every node group is an asset whose catalog id is a line of the file: the
     groups with a BSDF output in the catalog `Shader`, the others in
     `Shader/Gloffuse Helpers`;
  2. every group has a preview picture that is not a placeholder: the right
     size, not one flat colour, the sphere (centre) brighter than the dark
     lower studio sky (bottom corners); with --previews DIR, each shader
     group's preview is written there as NAME.png for the test to compare;
  3. where Blender stores them (3.6+), licence and copyright; always a
     description, the author and the tag `gloffuse`;
  4. nothing else in the file: no objects, meshes, cameras, lights, materials,
     worlds or collections, no render results, one scene.
Writes RESULT.json (what it saw, and "failures") and exits 1 on any failure.
"""
import argparse
import json
import os
import sys
import traceback

import bpy

SHADER_CATALOG = "Shader"
HELPER_CATALOG = "Shader/Gloffuse Helpers"


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--blend", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--previews", help="write each shader group's preview here as NAME.png")
    return parser.parse_args(argv)


def catalogs_beside(blend):
    """{path: uuid} of the definition file beside `blend`."""
    path = os.path.join(os.path.dirname(os.path.abspath(blend)), "blender_assets.cats.txt")
    catalogs = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#") or line.startswith("VERSION"):
                continue
            uuid, catalog_path = line.split(":")[:2]
            catalogs[catalog_path] = uuid
    return catalogs


def output_names(tree):
    if hasattr(tree, "interface"):  # 4.0+
        return [item.name for item in tree.interface.items_tree
                if getattr(item, "in_out", None) == "OUTPUT"]
    return [socket.name for socket in tree.outputs]


def preview_stats(tree):
    """What the preview shows: its size, the alpha of the corners and the centre,
    and the luminance of the sphere's upper and lower quarter."""
    preview = tree.preview
    if preview is None:
        return None
    width, height = preview.image_size
    pixels = list(preview.image_pixels_float)
    if width * height == 0 or len(pixels) != 4 * width * height:
        return {"size": [width, height]}

    def at(x, y, channel):  # y = 0 is the bottom row
        return pixels[4 * (y * width + x) + channel]

    def luma(x, y):
        return sum(w * at(x, y, c) for c, w in enumerate((0.2126, 0.7152, 0.0722)))

    def band(y0, y1):
        values = [luma(x, y) for x in range(width * 3 // 8, width * 5 // 8)
                  for y in range(int(height * y0), int(height * y1))]
        return sum(values) / len(values)

    return {
        "size": [width, height],
        "corner_alpha": max(at(x, y, 3) for x in (0, width - 1) for y in (0, height - 1)),
        "centre_alpha": at(width // 2, height // 2, 3),
        "upper": band(0.6, 0.75),
        "lower": band(0.25, 0.4),
    }


def check(blend):
    failures = []
    catalogs = catalogs_beside(blend)
    bpy.ops.wm.open_mainfile(filepath=blend)
    seen = {"groups": {}, "catalogs": catalogs}
    for path in (SHADER_CATALOG, HELPER_CATALOG):
        if path not in catalogs:
            failures.append("the catalog file has no catalog %r" % path)
    for tree in bpy.data.node_groups:
        data = tree.asset_data
        has_bsdf = "BSDF" in output_names(tree)
        entry = {"bsdf": has_bsdf}
        seen["groups"][tree.name] = entry
        if data is None:
            failures.append("%s: not an asset" % tree.name)
            continue
        entry["catalog_id"] = data.catalog_id
        want = SHADER_CATALOG if has_bsdf else HELPER_CATALOG
        if data.catalog_id != catalogs.get(want):
            failures.append("%s: catalog id %s is not the file's %r (%s)"
                            % (tree.name, data.catalog_id, want, catalogs.get(want)))
        if not data.description:
            failures.append("%s: no description" % tree.name)
        if "gloffuse" not in [t.name for t in data.tags]:
            failures.append("%s: no tag 'gloffuse'" % tree.name)
        if data.author != "gloffuse":
            failures.append("%s: author %r" % (tree.name, data.author))
        if bpy.app.version >= (3, 6, 0):
            entry["license"] = data.license
            entry["copyright"] = data.copyright
            if data.license != "CC0-1.0" or not data.copyright:
                failures.append("%s: licence %r, copyright %r" % (tree.name, data.license,
                                                                  data.copyright))
        stats = preview_stats(tree)
        entry["preview"] = stats
        if stats is None or "upper" not in stats:
            failures.append("%s: no preview picture (%s)" % (tree.name, stats))
            continue
        shape = {k: stats[k] for k in ("size", "corner_alpha", "centre_alpha", "upper", "lower")}
        # A sphere on a transparent background, lit from above by the studio sky.
        if stats["size"][0] < 64 or stats["corner_alpha"] > 0.01 or stats["centre_alpha"] < 0.99:
            failures.append("%s: the preview is no sphere: %s" % (tree.name, shape))
        elif not stats["upper"] > stats["lower"] + 0.05:
            failures.append("%s: the preview's sphere is not lit from above: %s"
                            % (tree.name, shape))

    stray = {}
    for kind in ("objects", "meshes", "cameras", "lights", "materials", "worlds",
                 "collections", "curves", "fonts"):
        names = [block.name for block in getattr(bpy.data, kind)]
        if names:
            stray[kind] = names
    renders = [i.name for i in bpy.data.images if i.type != "IMAGE" or i.users == 0]
    if renders:
        stray["images"] = renders
    if len(bpy.data.scenes) != 1:
        stray["scenes"] = [s.name for s in bpy.data.scenes]
    seen["stray"] = stray
    if stray:
        failures.append("stray datablocks: %s" % stray)
    return seen, failures


def write_previews(directory):
    """Each shader group's preview as DIRECTORY/NAME.png (after the checks: the
    images made here are not the file's)."""
    os.makedirs(directory, exist_ok=True)
    for tree in bpy.data.node_groups:
        if "BSDF" not in output_names(tree) or tree.preview is None:
            continue
        width, height = tree.preview.image_size
        image = bpy.data.images.new(tree.name, width, height, alpha=True)
        image.pixels = list(tree.preview.image_pixels_float)
        image.filepath_raw = os.path.join(directory, tree.name + ".png")
        image.file_format = "PNG"
        image.save()


def main():
    options = args()
    try:
        seen, failures = check(options.blend)
        if options.previews:
            write_previews(options.previews)
    except Exception:  # report, do not hide: the test prints the result
        seen, failures = {}, [traceback.format_exc()]
    seen["blender_version"] = bpy.app.version_string
    seen["failures"] = failures
    with open(options.out, "w", encoding="utf-8") as f:
        json.dump(seen, f, indent=1)
    for failure in failures:
        print("FAIL:", failure)
    sys.exit(1 if failures else 0)


main()
