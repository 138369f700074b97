# ---------------------------------------------------------------------------
# gloffuse audit_job.py: the main of `gloffuse audit`, one Blender run per
# user's .blend file (the audit's shared interface, issue 21).
#
# The job module of the audit script: the gloffuse binary bundles it with the
# modules it imports, after the header that defines GLOFFUSE_PARAMS, and ends
# the script with main(GLOFFUSE_PARAMS). It opens the user's file (never
# saving it), scans every material (audit_rules.py), then turns the file's
# scene into the furnace (furnace.py): each material on a closed UV sphere of
# its own, rendered once, then the same spheres with each material's conserving
# twin in its place (same position, same coordinates), rendered again. It
# prints one line
#   GLOFFUSE_RESULT {json}
# Rust reads the two EXRs back and judges. Asked to fix (--save, with the
# document's "fix" list of the materials Rust chose from an earlier run's
# verdicts), the job applies those materials' replacements, saves the copy and
# audits the copy instead. A material that cannot be audited gets an error and
# the run goes on; a file that cannot be opened exits 1 (run_main). Each
# material's `gloffuse_ignore` properties (its own and its nodes', into its
# groups) are reported as they are, under "waivers": gloffuse parses them.
# ---------------------------------------------------------------------------
import json
import os
import sys
import time

import bpy

from .audit_rules import (
    MULTISCATTER_TWIN,
    TWIN_KINDS,
    applicable_rules,
    scan_material,
    scan_scenes,
    twin_groups,
    uv_maps_named,
)
from .audit_twin import (
    apply_finding,
    datablock_pointers,
    has_replacement,
    make_twin,
    remove_unused_added,
    restore_groups,
    set_aside_groups,
)
from .compat import blender_version_string, filter_glossy_property, material_node_tree
from .contract import check_fields
from .furnace import (
    FURNACE_UV_MAP,
    furnace_layout,
    furnace_place_materials,
    furnace_stage,
    render_sweep,
)
from .groups import build_all, group_names
from .params import resolve_params
from .runtime import (
    ScriptArgumentParser,
    parse_script_args,
    result_line,
    run_main,
    save_blend,
    shown_path,
)

# Cycles' path depth in the audit: deep enough that light inside a solid glass
# sphere, through layers of alpha and in a scattering volume loses next to
# nothing to the bounce limit (the twins are judged against 1.0).
AUDIT_BOUNCES = {"max_bounces": 64, "diffuse_bounces": 8, "glossy_bounces": 64,
                 "transmission_bounces": 64, "transparent_max_bounces": 64, "volume_bounces": 16}


# The custom property that carries a waiver (crates/gloffuse/src/audit/waivers.rs
# reads its text; the job only reports it).
WAIVER_PROPERTY = "gloffuse_ignore"

# Blender holds at most 8 UV maps on a mesh.
UV_MAPS_MAX = 8


class AuditParamsError(ValueError):
    """The parameter document's "audit" section is missing or malformed."""


def audit_require(cond, message):
    if not cond:
        raise AuditParamsError("audit parameters: " + message)


def audit_params(document):
    """The "audit" section, checked; numbers as the furnace wants them."""
    audit_require(isinstance(document, dict), "the parameter document must be an object")
    check_fields(document, "audit_document", "the audit job's document")
    section = document.get("audit")
    audit_require(isinstance(section, dict), "the document has no \"audit\" object")
    render = bool(section.get("render", True))
    for key in ("output", "twin_output"):
        audit_require(not render or isinstance(section.get(key), str), "%r must be a path" % key)
    audit_require(isinstance(section.get("rules"), list), "\"rules\" must be a list")
    for key in ("cell", "samples"):
        audit_require(isinstance(section.get(key), int) and section[key] >= 1,
                      "%r must be a positive integer" % key)
    fix = section.get("fix", [])
    audit_require(isinstance(fix, list) and all(isinstance(item, dict) for item in fix),
                  "\"fix\" must be a list of {\"material\": index, \"scale\": number or null}")
    return dict(section, render=render, engine="cycles", solid=True, fix=fix,
                seed=int(section.get("seed", 0)),
                threads=int(section.get("threads", 0)),
                radius_fraction=float(section.get("radius_fraction", 0.9)))


# --- scanning ---------------------------------------------------------------------

def scan_file(rules, groups):
    """One entry per (non Grease Pencil) material: its result fields and, under
    "_material", the datablock. A failing material gets an error, never the run."""
    entries = []
    for material in bpy.data.materials:
        if material.is_grease_pencil:
            continue
        entry = {"name": material.name,
                 "library": material.library.filepath if material.library else None,
                 "users": material.users, "cell": None, "twin_cell": None, "replaced": 0,
                 "findings": [], "error": None, "waivers": [], "_material": material}
        try:
            entry["findings"], entry["error"] = scan_material(material, rules, groups)
        except Exception as error:  # one material's problem is its own
            entry["error"] = "scan failed: %s: %s" % (type(error).__name__, error)
        try:
            entry["waivers"] = material_waivers(material)
        except Exception as error:  # a waiver that cannot be read waives nothing
            entry["waivers"] = [waiver_entry([material.name], "Material", error)]
        entries.append(entry)
    return entries


def waiver_entry(path, node_type, value):
    """A waiver as the result line carries it: its text, or only its type when
    it is not text (an int, a group of properties, what reading it raised)."""
    text = value if isinstance(value, str) else None
    return {"node": path, "node_type": node_type, "value": text, "type": type(value).__name__}


def material_waivers(material):
    """The `gloffuse_ignore` properties of `material` and of every node in its
    tree and, by group node, in the groups it uses (each group once per path)."""
    found = []
    if WAIVER_PROPERTY in material.keys():
        found.append(waiver_entry([material.name], "Material", material[WAIVER_PROPERTY]))
    tree = material_node_tree(material)
    todo = [(tree, [material.name], ())] if tree is not None else []
    while todo:
        tree, path, stack = todo.pop()
        for node in tree.nodes:
            node_path = path + [node.name]
            if WAIVER_PROPERTY in node.keys():
                found.append(waiver_entry(node_path, node.bl_idname, node[WAIVER_PROPERTY]))
            group = getattr(node, "node_tree", None) if node.bl_idname == "ShaderNodeGroup" else None
            if group is not None and group.name not in stack and len(stack) < 64:
                todo.append((group, node_path, stack + (group.name,)))
    return found


def group_needs(entries, groups):
    """The (mode, distribution) of every gloffuse group a twin uses, sorted
    (Blender's own Multiscatter GGX is no group)."""
    by_name = {name: (TWIN_KINDS[kind], distribution) for kind, names in groups.items()
               for distribution, name in names.items() if name != MULTISCATTER_TWIN}
    return sorted({by_name[name] for entry in entries for item in entry["findings"]
                   for name in (item["twin"], item.get("metal_twin")) if name in by_name})


# The generate document's group fields that twins use, and the mode of each.
TWIN_GROUP_FIELDS = (("layered_group", "layered"), ("anisotropic_group", "anisotropic"),
                     ("glass_group", "glass"), ("refraction_group", "glass"))


def provided_groups(document):
    """The (mode, distribution) of every twin group the document's generate
    part builds."""
    provided = set()
    for spec in document.get("groups") or []:
        if (spec.get("view") or {}).get("multiscatter_group"):
            provided.add(("multiscatter", spec["distribution"]))
        for field, mode in TWIN_GROUP_FIELDS:
            if spec.get(field):
                provided.add((mode, spec["distribution"]))
    return provided


def build_twin_groups(document):
    """Build the document's groups, the file's own of those names set aside
    (build_all would rebuild them in place). Returns what restore needs."""
    params = resolve_params(document)
    before = datablock_pointers()
    kept = set_aside_groups(group_names(params))
    build_all(params)
    return before, kept


def fix_and_save(entries, document, args, groups, fix):
    """Apply the replacements of the materials in `fix` (the document's list:
    entry index, and the scale of an Add Shader that creates energy) to the real
    materials (shared group trees in place), drop what this run added and
    nothing uses, save the copy."""
    chosen = {item["material"]: item.get("scale") for item in fix}
    built = build_twin_groups(document) if group_needs(entries, groups) else None
    replaced = materials = 0
    for index, entry in enumerate(entries):
        material = entry["_material"]
        tree = material_node_tree(material)
        if index not in chosen or entry["error"] is not None or tree is None \
                or material.library is not None:
            continue  # a linked material is its library's to fix
        findings = [dict(item, scale=chosen[index]) for item in entry["findings"]]
        count = sum(1 for item in findings if apply_finding(tree, item))
        replaced += count
        materials += 1 if count else 0
    if built is not None:
        remove_unused_added(built[0])
        restore_groups(built[1])
    keep_unused_materials()
    path = save_blend(args.save, args.compress)
    return {"path": shown_path(path), "replaced": replaced, "materials": materials}


def keep_unused_materials():
    """Blender writes nothing that has no users, so a material no object uses would
    be missing from the fixed copy: a fake user keeps it (as the file had it)."""
    for material in bpy.data.materials:
        if material.library is None and material.users == 0:
            material.use_fake_user = True


# --- the furnace -------------------------------------------------------------------

def twins_and_cells(entries):
    """Make each material's twin and give every renderable material its grid
    cell, in order; returns the materials and their twins (None: no twin)."""
    materials, twins = [], []
    for entry in entries:
        if entry["error"] is not None:
            continue
        try:
            twin, entry["replaced"] = make_twin(entry["_material"], entry["findings"])
        except Exception as error:
            entry["error"] = "twin failed: %s: %s" % (type(error).__name__, error)
            continue
        entry["cell"] = len(materials)
        materials.append(entry["_material"])
        twins.append(twin)
    return materials, twins


def clear_scene(scene):
    """Unlink every object and child collection from the scene, and its
    background set (in memory only)."""
    scene.background_set = None
    for obj in list(scene.collection.objects):
        scene.collection.objects.unlink(obj)
    for child in list(scene.collection.children):
        scene.collection.children.unlink(child)


def audit_render_settings(scene):
    """What a user's scene may have changed that the furnace of verify never
    meets: path depth, caustics, Filter Glossy, simplify, overrides, layers."""
    cycles, render = scene.cycles, scene.render
    setattr(cycles, filter_glossy_property(cycles), 0.0)
    for key, value in AUDIT_BOUNCES.items():
        setattr(cycles, key, value)
    cycles.caustics_reflective = True
    cycles.caustics_refractive = True
    cycles.film_exposure = 1.0
    cycles.use_fast_gi = False
    cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    cycles.filter_width = 1.5
    render.use_simplify = False
    render.use_motion_blur = False
    render.use_multiview = False
    render.use_freestyle = False
    render.use_single_layer = True
    for layer in scene.view_layers:
        layer.material_override = None
        layer.samples = 0
        layer.use = True
        layer.use_solid = True


def give_uv_maps(objects, materials, twins):
    """Each sphere holds, beside its own UV map, every UV map its material (or
    twin) names, all the sphere's unwrap: a glTF import's UV Map and Tangent
    nodes name theirs, and a name the mesh lacks reads 0 everywhere."""
    shared = {}
    for obj, material, twin in zip(objects, materials, twins):
        names = uv_maps_named(material) | (uv_maps_named(twin) if twin is not None else set())
        names = tuple(sorted(names - {FURNACE_UV_MAP, ""}))[:UV_MAPS_MAX - 1]
        if not names:
            continue
        if names not in shared:
            mesh = obj.data.copy()
            for name in names:
                mesh.uv_layers.new(name=name, do_init=True)  # a copy of the active map
            shared[names] = mesh
        obj.data = shared[names]


def show_twins(objects, twins):
    """Put each twin on its material's sphere; spheres without a twin are not
    rendered. Returns whether any twin is shown."""
    for obj, twin in zip(objects, twins):
        if twin is None:
            obj.hide_render = True
        else:
            obj.material_slots[0].material = twin
    return any(twin is not None for twin in twins)


def furnace_render(entries, audit):
    """Twins, the furnace in the context scene, the materials' render, then the
    twins' on the same spheres. Returns None when no material can be rendered,
    else {"scene", "columns", "seconds", "twin_output"}; each entry's
    "twin_cell" is its twin's cell in the two renders stacked (the twins' below
    the materials'), or its own cell when it has no twin."""
    materials, twins = twins_and_cells(entries)
    if not materials:
        return None
    scene = bpy.context.scene
    # Laid out from the cells made, not from what gloffuse counted before.
    columns, rows = furnace_layout(len(materials), audit["cell"])
    clear_scene(scene)
    furnace_stage(scene, audit, columns, rows)
    audit_render_settings(scene)
    objects = furnace_place_materials(scene, audit, materials, columns, rows)
    give_uv_maps(objects, materials, twins)
    output = os.path.abspath(audit["output"])
    seconds = render_sweep(output)
    twin_output = None
    if show_twins(objects, twins):
        twin_output = os.path.abspath(audit["twin_output"])
        seconds += render_sweep(twin_output)
    for entry in entries:
        if entry["cell"] is not None:
            has_twin = twins[entry["cell"]] is not None
            entry["twin_cell"] = entry["cell"] + (columns * rows if has_twin else 0)
    return {"scene": scene, "columns": columns, "seconds": seconds, "twin_output": twin_output}


# --- main ----------------------------------------------------------------------------

def open_user_file(path):
    """Open the user's file (never saved: the audit only reads it). Returns its
    path and what Blender reported as an error while it still loaded the file
    (a strip it could not read, say), or None: such a file is audited, and the
    report becomes a file finding."""
    path = os.path.abspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError("no .blend file at %s" % path)
    try:
        bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
    except RuntimeError as error:
        # bpy raises on any error report, also when the read went on and the file
        # is open; a file that did not load is still this error.
        if not bpy.data.filepath or not os.path.samefile(bpy.data.filepath, path):
            raise
        return path, str(error).strip()
    return path, None


def load_findings(rules, said):
    """The file finding of what Blender reported while loading the file."""
    if said is None or "load-warning" not in rules:
        return []
    return [{"rule": "load-warning", "node": ["file"], "node_type": "File",
             "detail": {"blender_said": said}, "twin": None}]


def parse_audit_args(argv=None):
    """The file's paths travel as arguments, not in the document: a file name need not be
    UTF-8 (JSON holds only text), and an argument reaches Python byte for byte
    (surrogate-escaped), which Blender turns back into the very bytes when it opens or
    saves the path."""
    parser = ScriptArgumentParser(prog="gloffuse-audit",
                                  description="Audit the materials of one .blend file.")
    parser.add_argument("--open", metavar="IN.blend", required=True,
                        help="the .blend file to audit (opened, never saved)")
    parser.add_argument("--save", metavar="OUT.blend",
                        help="save a fixed copy here (default: no fix)")
    parser.add_argument("--compress", action="store_true",
                        help="save the fixed copy compressed (as the file opened was)")
    return parse_script_args(parser, argv)


def audit_main(document_text):
    document = json.loads(document_text)
    audit = audit_params(document)
    args = parse_audit_args()
    rules = applicable_rules(audit["rules"])
    groups = twin_groups(audit)
    path, said = open_user_file(args.open)

    start = time.perf_counter()
    file_findings = load_findings(rules, said) + scan_scenes(rules)
    entries = scan_file(rules, groups)
    scan_seconds = time.perf_counter() - start

    needs = group_needs(entries, groups) if audit["render"] or args.save else []
    missing = [need for need in needs if need not in provided_groups(document)]
    if missing:
        # The groups' tables take gloffuse seconds to compute: it sends them only
        # to a job that asks, and runs it again.
        print(result_line("audit_result", {"blender_version": blender_version_string(), "file": shown_path(path),
                           "materials": [], "needs": missing, "scan_seconds": scan_seconds}))
        sys.stdout.flush()
        return

    fixed = None
    if args.save:
        fixed = fix_and_save(entries, document, args, groups, audit["fix"])
        # What is judged now is the copy as saved.
        path, said = open_user_file(args.save)
        file_findings = load_findings(rules, said) + scan_scenes(rules)
        entries = scan_file(rules, groups)

    rendered = None
    if audit["render"]:
        if needs:
            build_twin_groups(document)
        rendered = furnace_render(entries, audit)
    else:
        for entry in entries:
            entry["replaced"] = sum(1 for item in entry["findings"] if has_replacement(item))

    scene = rendered["scene"] if rendered is not None else None
    result = {
        "blender_version": blender_version_string(),
        "file": shown_path(path),
        "output": os.path.abspath(audit["output"]) if scene is not None else None,
        "twin_output": rendered["twin_output"] if rendered is not None else None,
        "width": scene.render.resolution_x if scene is not None else 0,
        "height": scene.render.resolution_y if scene is not None else 0,
        "columns": rendered["columns"] if rendered is not None else None,
        "scan_seconds": round(scan_seconds, 3),
        "render_seconds": round(rendered["seconds"], 3) if rendered is not None else 0.0,
        "file_findings": file_findings,
        "materials": [{key: value for key, value in entry.items() if key != "_material"}
                      for entry in entries],
        "fixed": fixed,
    }
    print(result_line("audit_result", result))
    sys.stdout.flush()


def main(document_text):
    """The audit job on the parameter document `document_text` (JSON), with
    run_main's error handling: traceback, and exit 1 headless."""
    run_main(lambda: audit_main(document_text))
