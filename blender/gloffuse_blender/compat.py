# ---------------------------------------------------------------------------
# gloffuse compat.py: the compatibility shim. Every difference between the
# Blender versions gloffuse supports (3.4 .. 5.0 run; the binary, its Text
# Editor, or the `bpy` module) lives here and nowhere else. A newer Blender
# (5.1, 5.2: read in Cycles' source, not run; docs/BLENDER-VERSIONS.md) takes
# the newest branch: every check is `>=` or a feature test, never `==`.
#
# A module of the gloffuse_blender package; it imports none of the others.
# Functions and constants only. Every Blender version check of the package
# (bpy.app.version, or a feature test standing for one) is here.
# ---------------------------------------------------------------------------
import os

import bpy
import bmesh  # after bpy: under the bpy module, bmesh exists only once bpy is imported


# --- version -----------------------------------------------------------------

def blender_version_string():
    """Blender's version as "major.minor.patch" (no "LTS" suffix)."""
    return ".".join(str(part) for part in bpy.app.version)


def masking_family(height_correlated_from):
    """The masking family of this Blender's Cycles: "height-correlated" from
    the version the parameter document names (3.5), "separable" before it."""
    first = tuple(int(part) for part in height_correlated_from)
    return "height-correlated" if tuple(bpy.app.version[:2]) >= first else "separable"


def blender_at_least(version):
    """Whether this Blender is `version` ([major, minor]) or later."""
    return tuple(bpy.app.version[:2]) >= tuple(int(part) for part in version)


def valid_reflection_rule():
    """How Cycles raises a shading normal whose mirror reflection would dip
    below the surface (docs/PHYSICS.md §7): "3.0" (every BSDF, two candidate
    roots checked; Blender 3.0-3.5) or "3.6" (specular lobes only, one
    closed-form root; Blender 3.6 and later)."""
    return "3.6" if tuple(bpy.app.version[:2]) >= (3, 6) else "3.0"


def has_bump_map_correction():
    """The material setting Bump Map Correction (on by default), which can
    switch the normal correction off, exists from Blender 4.1."""
    return tuple(bpy.app.version[:2]) >= (4, 1)


def max_name_bytes():
    """Blender's name length limit in bytes (63 where it cannot be read)."""
    try:
        return bpy.types.ID.bl_rna.properties["name"].length_max - 1
    except (AttributeError, KeyError):
        return 63


# --- group interface (sockets) -------------------------------------------------

def has_interface_api(tree):
    """Blender 4.0+ describes group sockets with tree.interface."""
    return hasattr(tree, "interface")


# Blender 3.x encodes a float socket's subtype in the socket type name.
_LEGACY_SUBTYPE_SUFFIX = {"FACTOR": "Factor"}


def new_socket(tree, name, in_out, socket_type, subtype=None):
    """Append a group socket. in_out is 'INPUT' or 'OUTPUT'; socket_type is a
    base type name such as 'NodeSocketFloat'. Returns the interface socket,
    on which default_value, min_value, max_value and hide_value live."""
    if has_interface_api(tree):
        sock = tree.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
        set_socket_subtype(sock, subtype)
        return sock
    idname = socket_type + _LEGACY_SUBTYPE_SUFFIX.get(subtype, "")
    sockets = tree.inputs if in_out == "INPUT" else tree.outputs
    return sockets.new(idname, name)


def interface_sockets(tree, in_out):
    """The group's sockets of one direction, in order."""
    if has_interface_api(tree):
        return [item for item in tree.interface.items_tree
                if item.item_type == "SOCKET" and item.in_out == in_out]
    return list(tree.inputs if in_out == "INPUT" else tree.outputs)


def interface_has_panels(tree):
    if not has_interface_api(tree):
        return False
    return any(item.item_type != "SOCKET" for item in tree.interface.items_tree)


def socket_type_of(sock):
    """Base socket type name ('NodeSocketFloat', ...) of an interface socket."""
    if hasattr(sock, "socket_type"):
        return sock.socket_type
    idname = sock.bl_socket_idname  # 3.x: 'NodeSocketFloatFactor' and the like
    return "NodeSocketFloat" if idname.startswith("NodeSocketFloat") else idname


def signature_subtype(tree, subtype):
    """The part of a wanted socket's subtype that belongs in its signature (what
    must match for an existing socket to be kept): in 3.x the subtype is part
    of the socket type, so it is part of the signature there; 4.0+: None."""
    return subtype if not has_interface_api(tree) else None


def existing_signature_subtype(tree, sock):
    """The subtype a 3.x socket's type name encodes ('FACTOR' for
    NodeSocketFloatFactor), or None; always None in 4.0+."""
    subtype = None
    if not has_interface_api(tree):
        for key, suffix in _LEGACY_SUBTYPE_SUFFIX.items():
            if sock.bl_socket_idname == "NodeSocketFloat" + suffix:
                subtype = key
    return subtype


def set_socket_subtype(sock, subtype):
    """4.0+: an interface socket's subtype is a property (3.x: part of its type)."""
    if subtype and hasattr(sock, "subtype"):
        sock.subtype = subtype


def set_socket_description(sock, text):
    """The socket's tooltip, where the version has one."""
    if hasattr(sock, "description"):
        sock.description = text


def set_socket_hide_value(sock, hide):
    if hasattr(sock, "hide_value"):
        sock.hide_value = hide


def clear_interface(tree):
    """Remove every group socket (and panel)."""
    if has_interface_api(tree):
        tree.interface.clear()
    else:
        tree.inputs.clear()
        tree.outputs.clear()


# --- tree description and asset ---------------------------------------------

def set_tree_description(tree, text):
    """NodeTree.description exists from Blender 4.0 (shown as a tooltip)."""
    if hasattr(tree, "description"):
        tree.description = text


def mark_asset(tree, description, tags, asset=None):
    """Mark the group as an asset (Blender 3.0+) so it shows in the Asset
    Browser, with a description and tags, and from `asset` (nodes.py's
    asset_fields) its catalog, licence and copyright (those two from 3.6).
    Does nothing where unsupported."""
    if not hasattr(tree, "asset_mark"):
        return False
    if getattr(tree, "asset_data", None) is None:
        tree.asset_mark()
    data = getattr(tree, "asset_data", None)
    if data is None:
        return False
    if hasattr(data, "description"):
        data.description = description
    if hasattr(data, "author") and not data.author:
        data.author = "gloffuse"
    if hasattr(data, "tags"):
        present = {tag.name for tag in data.tags}
        for tag in tags:
            if tag not in present:
                data.tags.new(tag, skip_if_exists=True)
    for key, value in (asset or {}).items():
        if value is not None and hasattr(data, key):
            setattr(data, key, value)
    return True


# --- nodes -----------------------------------------------------------------------

def glossy_node(nodes, distribution):
    """A Glossy BSDF with an explicit distribution. In 4.0+ the Glossy node is
    the former Anisotropic node (idname ShaderNodeBsdfAnisotropic) and a new
    one defaults to MULTI_GGX, so the distribution is always set."""
    node = nodes.new("ShaderNodeBsdfGlossy")
    allowed = [item.identifier for item in
               node.bl_rna.properties["distribution"].enum_items]
    if distribution not in allowed:
        raise ValueError("Blender %s's Glossy BSDF has no distribution %r (it has %s)"
                         % (blender_version_string(), distribution, ", ".join(allowed)))
    node.distribution = distribution
    return node


def anisotropic_glossy_node(nodes, distribution):
    """Blender's anisotropic glossy BSDF with an explicit distribution: 4.0+'s
    Glossy BSDF (it has Anisotropy, Rotation and Tangent), 3.x's Anisotropic
    BSDF (its Glossy has none)."""
    if bpy.app.version >= (4, 0, 0):
        return glossy_node(nodes, distribution)
    node = nodes.new("ShaderNodeBsdfAnisotropic")
    node.distribution = distribution
    return node


def principled_coat_node(nodes):
    """A Principled BSDF that is its dielectric specular layer alone (Base
    Color black, Metallic 0, Multiscatter GGX), or None before 4.0. From 4.0
    Principled applies the exact dielectric Fresnel at each microfacet, takes
    its index from IOR (Specular IOR Level 0.5 keeps it), tints F0 by Specular
    Tint and compensates multiple scattering; 3.x's specular takes F0 from
    Specular and ignores Specular Tint over a black base."""
    if tuple(bpy.app.version[:2]) < (4, 0):
        return None
    node = nodes.new("ShaderNodeBsdfPrincipled")
    node.distribution = "MULTI_GGX"
    node.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    node.inputs["Metallic"].default_value = 0.0
    node.inputs["Emission Strength"].default_value = 0.0
    compat_principled_dielectric(node, 1.5)
    return node


def metallic_coat_node(nodes, distribution):
    """A Metallic BSDF of `distribution` in Physical Conductor mode with
    Extinction 0 and no thin film (its IOR input is the coat's index), or None
    before 5.0. Cycles 5.0 made that Fresnel the exact polarised conductor one,
    which with no extinction is the dielectric Fresnel; 4.3-4.5 evaluate an
    approximate form, 49 % high at IOR 1.5 (docs/PHYSICS.md §13)."""
    if tuple(bpy.app.version[:2]) < (5, 0):
        return None
    node = nodes.new("ShaderNodeBsdfMetallic")
    node.distribution = distribution
    node.fresnel_type = "PHYSICAL_CONDUCTOR"
    node.inputs["Extinction"].default_value = (0.0, 0.0, 0.0)
    node.inputs["Thin Film Thickness"].default_value = 0.0
    return node


def find_socket(sockets, identifier, name=None, socket_type=None):
    """The socket with this identifier; else (an identifier renamed in a
    newer Blender) the one enabled socket called `name` of type `socket_type`
    ('RGBA', 'VALUE', ...), as names and types are what the UI keeps."""
    for sock in sockets:
        if sock.identifier == identifier:
            return sock
    if name is not None:
        matches = [sock for sock in sockets
                   if sock.name == name and sock.type == socket_type
                   and getattr(sock, "enabled", True)]
        if len(matches) == 1:
            return matches[0]
    raise KeyError("Blender %s: no socket with identifier %r (nor one enabled %s socket %r)"
                   % (blender_version_string(), identifier, socket_type, name))


def multiply_color_node(nodes):
    """A colour multiply with factor 1: returns (node, a_in, b_in, out).
    ShaderNodeMix (3.4+) in RGBA/MULTIPLY mode, sockets found by identifier
    because several share the names A, B and Result; the legacy MixRGB node
    where ShaderNodeMix does not exist."""
    if hasattr(bpy.types, "ShaderNodeMix"):
        node = nodes.new("ShaderNodeMix")
        node.data_type = "RGBA"
        node.blend_type = "MULTIPLY"
        node.clamp_factor = True
        node.clamp_result = False
        fac = find_socket(node.inputs, "Factor_Float", "Factor", "VALUE")
        a = find_socket(node.inputs, "A_Color", "A", "RGBA")
        b = find_socket(node.inputs, "B_Color", "B", "RGBA")
        out = find_socket(node.outputs, "Result_Color", "Result", "RGBA")
    else:
        node = nodes.new("ShaderNodeMixRGB")
        node.blend_type = "MULTIPLY"
        node.use_clamp = False
        fac, a, b = node.inputs[0], node.inputs[1], node.inputs[2]
        out = node.outputs[0]
    fac.default_value = 1.0
    return node, a, b, out


def set_parent(node, frame):
    """Put node in frame. The frame sits at the origin, so a child's location
    means the same whether Blender stores it relative to the frame (before 4.4)
    or absolute (4.4+)."""
    node.parent = frame


# --- scenes (furnace.py, meshes.py, previews.py) --------------------------------

def compat_node_tree(id_block):
    """The node tree of a world or material, creating it where needed.
    3.x/4.x: node_tree is None until use_nodes is set; 5.0+: always present and
    use_nodes is deprecated, so it is only touched when there is no tree."""
    if id_block.node_tree is None and hasattr(id_block, "use_nodes"):
        id_block.use_nodes = True
    if id_block.node_tree is None:
        raise RuntimeError("%s %r has no node tree" % (type(id_block).__name__, id_block.name))
    return id_block.node_tree


def compat_camera_rays_only(obj):
    """Make an object visible to camera rays only (3.0+: Object.visible_*;
    2.9x: Object.cycles_visibility.*)."""
    flags = {"camera": True, "diffuse": False, "glossy": False, "transmission": False,
             "volume_scatter": False, "shadow": False}
    if hasattr(obj, "visible_diffuse"):
        for name, value in flags.items():
            setattr(obj, "visible_" + name, value)
    else:
        visibility = obj.cycles_visibility
        for name, value in flags.items():
            key = "scatter" if name == "volume_scatter" else name
            if hasattr(visibility, key):
                setattr(visibility, key, value)


def compat_disable_denoising(scene):
    scene.cycles.use_denoising = False
    for view_layer in scene.view_layers:
        if hasattr(view_layer, "cycles") and hasattr(view_layer.cycles, "use_denoising"):
            view_layer.cycles.use_denoising = False


def compat_disable_time_limit(cycles):
    """Cycles' render time limit (0 = none), where the version has one."""
    if hasattr(cycles, "time_limit"):
        cycles.time_limit = 0.0


def compat_exr_settings(settings):
    """Single-layer OpenEXR, RGBA, 32-bit float, ZIP (the exr crate reads ZIP,
    not DWAA/DWAB). 5.0 needs media_type before file_format."""
    if hasattr(settings, "media_type"):
        settings.media_type = "IMAGE"
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGBA"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    if hasattr(settings, "use_zbuffer"):
        settings.use_zbuffer = False
    if hasattr(settings, "use_preview"):
        settings.use_preview = False
    if hasattr(settings, "color_management"):
        settings.color_management = "FOLLOW_SCENE"


def compat_png_settings(settings):
    """PNG, RGBA (the previews). 5.0 needs media_type before file_format."""
    if hasattr(settings, "media_type"):
        settings.media_type = "IMAGE"
    settings.file_format = "PNG"
    settings.color_mode = "RGBA"


def compat_uv_sphere(bm, radius, segments, rings, uvs=False):
    # bmesh's create_uvsphere takes `radius` since 3.0 (`diameter`, which was
    # really a radius, before).
    try:
        bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=radius,
                                  calc_uvs=uvs)
    except TypeError:
        bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, diameter=radius,
                                  calc_uvs=uvs)


def compat_disable_auto_smooth(mesh):
    """Before 4.1 a mesh's Auto Smooth could split smooth normals; 4.1+ has none."""
    if hasattr(mesh, "use_auto_smooth"):
        mesh.use_auto_smooth = False


def compat_disable_post_processing(render):
    for name in ("use_compositing", "use_sequencer"):
        if hasattr(render, name):
            setattr(render, name, False)


def compat_principled_dielectric(node, ior):
    """Make a Principled BSDF (otherwise at its defaults) a dielectric of index
    `ior`. In 4.0+ its specular layer follows IOR (Specular IOR Level 0.5 keeps
    it as is). Before 4.0 IOR drives transmission only; the specular F0 is
    0.08 x Specular, so Specular = F0(ior) / 0.08 (above 1 for IOR > 1.79: the
    socket's range ends at 1 in the UI only, and Cycles uses the value). Cycles 5.2 adds Thin Wall (off by default; on,
    it changes transmission and subsurface only): pinned off where it exists,
    so the reference stays the opaque dielectric gloffuse models."""
    node.inputs["IOR"].default_value = ior
    thin_wall = node.inputs.get("Thin Wall")
    if thin_wall is not None:
        thin_wall.default_value = False
    if "Specular" in node.inputs:
        f0 = ((ior - 1.0) / (ior + 1.0)) ** 2
        node.inputs["Specular"].default_value = f0 / 0.08


def compat_eevee_engine():
    """EEVEE's render engine id: BLENDER_EEVEE_NEXT in 4.2-4.5, BLENDER_EEVEE
    in 3.x (Legacy) and 5.0+ (Next, renamed back)."""
    items = [item.identifier for item in
             bpy.types.RenderSettings.bl_rna.properties["engine"].enum_items]
    return "BLENDER_EEVEE_NEXT" if "BLENDER_EEVEE_NEXT" in items else "BLENDER_EEVEE"


def compat_eevee_furnace(scene, world, samples):
    """The EEVEE settings under which a white Diffuse sphere in a white world is
    100 % (Legacy) or 99.2 % (Next, a floor no setting lifts); docs/EEVEE.md
    has the measurements behind each."""
    eevee = scene.eevee
    eevee.taa_render_samples = samples
    if hasattr(eevee, "use_raytracing"):  # Next (4.2+)
        # Screen tracing sees the neighbouring spheres and the film (-4.6 %).
        eevee.use_raytracing = False
        # No light casts a shadow here; on: the same pixels, ~10x the time.
        eevee.use_shadows = False
        # The world probe's resolution sets the diffuse floor: 1024 (the
        # default) 99.22 %, 128 98.3 %, 4096 98.95 %.
        world.probe_resolution = "1024"
    else:  # Legacy (3.x)
        # Screen-space reflections pick up the transparent film (GGX r = 0.5:
        # -13 %); ambient occlusion shades the limb (-0.3 %); bloom adds light.
        eevee.use_ssr = False
        eevee.use_gtao = False
        eevee.use_bloom = False


# Inputs a newer Blender adds to a node it loads from an older file, at a value that
# renders as before: (input identifier, that value, inputs that only matter when it
# differs). 5.0 gives the Glass BSDF a thin film of thickness 0 (none).
_ADDED_INPUTS = (
    ("Thin Film Thickness", 0.0, ("Thin Film IOR",)),
)


def inputs_added_as_before(node):
    """Identifiers of `node`'s unlinked inputs that a newer Blender may have added
    when it loaded the file and that change nothing (_ADDED_INPUTS): a group
    gloffuse built in 4.5 renders the same in 5.0, so its fingerprint leaves
    them out."""
    unlinked = {sock.identifier: sock for sock in node.inputs if not sock.is_linked}
    left_out = set()
    for identifier, neutral, dependents in _ADDED_INPUTS:
        sock = unlinked.get(identifier)
        if sock is not None and getattr(sock, "default_value", None) == neutral:
            left_out.add(identifier)
            left_out.update(name for name in dependents if name in unlinked)
    return left_out


# --- the add-on (addon.py) ----------------------------------------------------

def addon_user_folder(package, name, create):
    """A folder for the add-on's own files under Blender's user resources: the
    extension's user directory (4.2+, package "bl_ext.REPOSITORY.gloffuse"), or,
    for the classic add-on (3.4 to 4.1, or a legacy add-on in 4.2+, package
    "gloffuse"), datafiles/PACKAGE/NAME; either survives the add-on's updates."""
    if package.startswith("bl_ext.") and hasattr(bpy.utils, "extension_path_user"):
        return bpy.utils.extension_path_user(package, path=name, create=create)
    return bpy.utils.user_resource("DATAFILES", path=os.path.join(package, name), create=create)


def add_asset_library(name, directory):
    """Register `directory` as the asset library `name`. Before 4.x the
    preferences' collection has no new(); its operator adds one named after the
    folder, renamed here."""
    libraries = bpy.context.preferences.filepaths.asset_libraries
    if hasattr(libraries, "new"):
        libraries.new(name=name, directory=directory)
        return
    # An add-on's register() runs in a restricted context, which bpy.ops's wrapper
    # refuses (it updates the view layer first); the operator itself needs none.
    from _bpy import ops as operators  # noqa: PLC0415 -- this one old path only

    operators.call("preferences.asset_library_add", None, {"directory": directory})
    libraries[-1].name = name


def remove_asset_library(library):
    """Unregister an asset library of the preferences (by its operator before 4.x)."""
    libraries = bpy.context.preferences.filepaths.asset_libraries
    if hasattr(libraries, "remove"):
        libraries.remove(library)
        return
    from _bpy import ops as operators  # noqa: PLC0415 -- as add_asset_library

    operators.call("preferences.asset_library_remove", None,
                   {"index": list(libraries).index(library)})


# --- audit (audit_rules.py, audit_twin.py, audit_job.py) ---------------------------

def version_in_range(first, before):
    """Whether this Blender is at least `first` ([major, minor]) and below
    `before` (or `before` is None): a rule's range in the audit document."""
    version = tuple(bpy.app.version[:2])
    return version >= tuple(first) and (before is None or version < tuple(before))


def filter_glossy_property(cycles):
    """The name of Cycles' Filter Glossy setting: `blur_glossy` (3.x to 5.0 at
    least), `filter_glossy` where a newer Cycles renames it."""
    return "filter_glossy" if hasattr(cycles, "filter_glossy") else "blur_glossy"


# Principled BSDF inputs renamed in 4.0, newest name first.
_PRINCIPLED_INPUTS = {
    "transmission": ("Transmission Weight", "Transmission"),
    "subsurface": ("Subsurface Weight", "Subsurface"),
    "emission_color": ("Emission Color", "Emission"),
    "specular": ("Specular",),  # 3.x only: F0 = 0.08 x Specular (4.0+ takes IOR)
    "thin_wall": ("Thin Wall",),  # 5.2 on
}


def principled_input(node, role):
    """The Principled BSDF input playing `role` (a key of _PRINCIPLED_INPUTS)
    in this Blender, or None where it has no such input."""
    for name in _PRINCIPLED_INPUTS[role]:
        sock = node.inputs.get(name)
        if sock is not None:
            return sock
    return None


def is_missing(id_block):
    """A linked datablock or library whose file was not found on load. ID.is_missing
    exists from 4.x; before it, a library is missing when its file does not exist."""
    if hasattr(id_block, "is_missing"):
        return bool(id_block.is_missing)
    if isinstance(id_block, bpy.types.Library):
        return not os.path.isfile(bpy.path.abspath(id_block.filepath))
    return False


def material_node_tree(material):
    """The node tree a material renders with, or None (no nodes: before 5.0
    a material can have use_nodes off, and then renders its plain colour)."""
    if not getattr(material, "use_nodes", True):
        return None
    return material.node_tree
