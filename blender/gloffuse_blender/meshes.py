# ---------------------------------------------------------------------------
# gloffuse meshes.py: the smooth UV-sphere mesh the furnace, the previews and
# the tests' material scene render.
#
# A module of the gloffuse_blender package. Functions only; the version
# differences of building a sphere go through compat.py.
#
#   sphere_mesh(name, radius, segments, rings, cut_below=None, uv_map=None) -> mesh
# ---------------------------------------------------------------------------
import bpy
import bmesh  # after bpy: under the bpy module, bmesh exists only once bpy is imported

from .compat import compat_disable_auto_smooth, compat_uv_sphere


def sphere_mesh(name, radius, segments, rings, cut_below=None, uv_map=None):
    """A new smooth-shaded UV sphere mesh `name` around the origin, with one
    empty material slot; with `cut_below`, the vertices below that height are
    dropped (and the faces they belong to); with `uv_map`, a UV map of that
    name (the sphere's own unwrap)."""
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    if uv_map is not None:
        bm.loops.layers.uv.new(uv_map)  # create_uvsphere fills the active UV layer
    compat_uv_sphere(bm, radius, segments, rings, uv_map is not None)
    if cut_below is not None:
        bmesh.ops.delete(bm, geom=[v for v in bm.verts if v.co.z < cut_below], context="VERTS")
    bm.to_mesh(mesh)
    bm.free()
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    compat_disable_auto_smooth(mesh)
    mesh.materials.append(None)
    mesh.update()
    return mesh
