# SPDX-License-Identifier: GPL-3.0-or-later
# Copyright (C) 2026 the gloffuse authors
"""gloffuse: Blender's glossy BSDFs at full brightness, as an asset library.

The extension (Blender 4.2+), or the same add-on packed as a classic add-on
(3.4 to 4.1), bundles a library .blend of gloffuse node groups (CC0) and its
asset catalogs. Enabling it copies them into the add-on's user folder (its own
folder is replaced on every update and may be read-only; compat.py's
addon_user_folder) and registers that directory as the asset library "Gloffuse"; disabling it
removes the library again. The groups then show in the Asset Browser and, in
the shader editor, under Add > Shader.

It also brings the audit into Blender (panel_ui.py): a "Gloffuse" panel in
Properties > Material and a "Gloffuse" tab in the Shader Editor's sidebar, and
the operators gloffuse.audit_material, gloffuse.audit_file and
gloffuse.fix_material. The gloffuse binary bundles the modules this one imports
into the extension's __init__.py, beside the catalogue they read.
"""
import filecmp
import os
import shutil

import bpy

from .compat import add_asset_library, addon_user_folder, remove_asset_library
from .panel_ui import register_panel, unregister_panel

LIBRARY_NAME = "Gloffuse"
BUNDLED = os.path.join(os.path.dirname(__file__), "library")


def _user_library():
    """The library folder in the extension's user directory, brought up to date
    with the bundled files (each replaced whole, never half-written)."""
    directory = addon_user_folder(__package__, "library", create=True)
    for name in sorted(os.listdir(BUNDLED)):
        source = os.path.join(BUNDLED, name)
        target = os.path.join(directory, name)
        if os.path.isfile(target) and filecmp.cmp(source, target, shallow=False):
            continue
        partial = target + ".partial"
        shutil.copyfile(source, partial)
        os.replace(partial, target)
    return directory


def _registered(directory):
    libraries = bpy.context.preferences.filepaths.asset_libraries
    wanted = os.path.normcase(os.path.realpath(directory))
    for library in libraries:
        if os.path.normcase(os.path.realpath(bpy.path.abspath(library.path))) == wanted:
            return library
    return None


def register():
    register_panel(os.path.dirname(__file__))
    directory = _user_library()
    if _registered(directory) is None:
        # Blender's default import method for a new library (Append (Reuse Data)
        # in 4.x, Pack in 5.0) copies a group into the user's file: materials keep
        # working after the extension is disabled or removed.
        add_asset_library(LIBRARY_NAME, directory)


def unregister():
    unregister_panel()
    directory = addon_user_folder(__package__, "library", create=False)
    library = _registered(directory)
    if library is not None:
        remove_asset_library(library)
