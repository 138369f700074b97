# SPDX-License-Identifier: GPL-3.0-or-later
# Copyright (C) 2026 the gloffuse authors
"""gloffuse: Blender's glossy BSDFs at full brightness, as an asset library.

The extension bundles a library .blend of gloffuse node groups (CC0) and its
asset catalogs. Enabling it copies them into the extension's user directory
(the extension's own folder is replaced on every update and may be read-only)
and registers that directory as the asset library "Gloffuse"; disabling it
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

from .panel_ui import register_panel, unregister_panel

LIBRARY_NAME = "Gloffuse"
BUNDLED = os.path.join(os.path.dirname(__file__), "library")


def _user_library():
    """The library folder in the extension's user directory, brought up to date
    with the bundled files (each replaced whole, never half-written)."""
    directory = bpy.utils.extension_path_user(__package__, path="library", create=True)
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
        bpy.context.preferences.filepaths.asset_libraries.new(
            name=LIBRARY_NAME, directory=directory)


def unregister():
    unregister_panel()
    directory = bpy.utils.extension_path_user(__package__, path="library", create=False)
    library = _registered(directory)
    if library is not None:
        bpy.context.preferences.filepaths.asset_libraries.remove(library)
