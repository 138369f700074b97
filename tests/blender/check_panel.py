"""Checks the gloffuse extension's audit panel and operators (issue 42) in real
Blender 4.2+ (the bpy module), or the classic add-on's in 3.4 to 4.1 (with --addon),
against `gloffuse audit` as the oracle:

    python check_panel.py -- --zip gloffuse.zip [--addon] --user-resources EMPTY_DIR \
        --oracle ORACLE.json --fix-report FIX.json --fixed-dir FIXED_DIR --out RESULT.json FILE.blend ...

ORACLE.json: `gloffuse audit --no-render --json FILE.blend ...`; FIX.json and
FIXED_DIR: the report of `gloffuse audit --no-render --json --fix-dir FIXED_DIR
FILE.blend ...` (which materials it rewrote) and where it wrote the fixed copies
(by file name). In one Blender:

  1. the zip installs and enables headless (`bpy.ops.extensions.package_install_files`
     into the "user_default" repository; a classic add-on by `preferences.addon_install`
     and `addon_enable`), in a fresh user-resources folder, and registers its asset
     library; the three
     operators exist, and the two that change data have REGISTER and UNDO;
  2. per file: before an audit every material is "not-judged"; gloffuse.audit_material
     (each material made active in turn) and then gloffuse.audit_file give each
     material the oracle's verdict, reason, findings (rule, node path, fix, why as the
     oracle's first words) and predictions (within MAX_PREDICTION_ERROR, the
     catalogue's interpolation bound), and as mean the darkest predicted lobe;
  3. each panel's draw() runs with a recording layout (a stand-in for Blender's
     UILayout that records what is drawn) and shows the verdict and every finding
     (unwrapped without a region; wrapped, the labels put together are the text);
     the "All materials" list puts failures first; a finding's show-node button is
     drawn only when the editor shows the tree that holds its node;
  4. gloffuse.fix_material on the first material the oracle rewrote, then Blender's
     own undo (ed.undo_push / ed.undo: the operator's UNDO push is the UI's, which a
     Python call without a window does not make, so the test pushes the two steps the
     UI would) restores the tree exactly, and redo brings the fix back;
  5. gloffuse.fix_material on every material: it fixes exactly the materials the
     oracle rewrote, each one's verdict is then the oracle's after its fix, and each
     material's tree equals its tree in the oracle's fixed copy (appended from
     FIXED_DIR).
Writes RESULT.json (what it saw, and "failures") and exits 1 on any failure.
"""
import argparse
import json
import os
import re
import shutil
import sys
import tempfile
import traceback
import types

MAX_PREDICTION_ERROR = 5e-4  # crates/gloffuse/src/audit/catalogue.rs MAX_INTERPOLATION_ERROR


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--zip", required=True)
    parser.add_argument("--addon", action="store_true", help="the zip is a classic add-on")
    parser.add_argument("--user-resources", required=True)
    parser.add_argument("--oracle", required=True)
    parser.add_argument("--fix-report", required=True)
    parser.add_argument("--fixed-dir", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("files", nargs="+")
    return parser.parse_args(argv)


OPTIONS = args()
# Where Blender keeps a user's add-ons and their files: read at start-up by 4.2+'s bpy
# module, at each use by 3.4 (which knows only the three separate folders).
os.environ["BLENDER_USER_RESOURCES"] = OPTIONS.user_resources
for _kind in ("SCRIPTS", "DATAFILES", "CONFIG"):
    os.environ["BLENDER_USER_" + _kind] = os.path.join(OPTIONS.user_resources, _kind.lower())

import bpy  # noqa: E402 -- after the environment it reads at start-up

MODULE = "gloffuse" if OPTIONS.addon else "bl_ext.user_default.gloffuse"
TWIN_GROUP = re.compile(r"^Gloffuse (Multiscatter|Layered) \(")


# --- a recording layout ------------------------------------------------------------------

class Recorder:
    """Stands in for bpy.types.UILayout: records every label and operator button drawn
    (in order) in `drawn`, shared by the sub-layouts it hands out."""

    def __init__(self, drawn=None):
        self.drawn = [] if drawn is None else drawn
        self.enabled = self.active = self.alert = True

    def _sub(self, *_args, **_kwargs):
        return Recorder(self.drawn)

    row = column = box = split = _sub

    def label(self, text="", icon="NONE"):
        self.drawn.append({"label": text, "icon": icon})

    def operator(self, idname, text=None, icon="NONE"):
        entry = {"operator": idname, "text": text, "icon": icon, "properties": {}}
        self.drawn.append(entry)
        return OperatorProperties(entry)

    def separator(self, *_args, **_kwargs):
        pass

    def prop(self, data, name, **kwargs):
        self.drawn.append({"prop": name, "value": getattr(data, name)})


class OperatorProperties:
    def __init__(self, entry):
        object.__setattr__(self, "_entry", entry)

    def __setattr__(self, name, value):
        self._entry["properties"][name] = value


def draw(panel_class, context):
    layout = Recorder()
    panel_class.draw(types.SimpleNamespace(layout=layout), context)
    return layout.drawn


def labels(drawn):
    return [entry["label"] for entry in drawn if "label" in entry]


# --- trees -------------------------------------------------------------------------------

def plain(name):
    return re.sub(r"\.\d{3}$", "", name)


def value_of(socket):
    value = getattr(socket, "default_value", None)
    if isinstance(value, float):
        return round(value, 5)
    if value is None or isinstance(value, (bool, int, str)):
        return value
    try:
        return [round(float(v), 5) for v in value]
    except TypeError:
        return repr(value)


def describe(tree, stack=()):
    """What a tree renders with, names of appended copies (X.001) made plain: each node's
    type, distribution, group, mute and unlinked input values, and the links; groups
    described inside, except gloffuse's own twin groups (the extension's library and the
    command line build those apart)."""
    nodes = {}
    for node in tree.nodes:
        if node.bl_idname == "NodeFrame":
            continue
        group = getattr(node, "node_tree", None) if node.bl_idname == "ShaderNodeGroup" else None
        inner = None
        if group is not None and group.name not in stack:
            own = TWIN_GROUP.match(group.name) and "gloffuse" in group.keys()
            inner = "gloffuse twin group" if own else describe(group, stack + (group.name,))
        nodes[node.name] = {
            "type": node.bl_idname, "mute": node.mute,
            "distribution": getattr(node, "distribution", None),
            "group": plain(group.name) if group is not None else None, "inner": inner,
            "inputs": [[s.identifier, value_of(s)] for s in node.inputs if not s.is_linked],
        }
    links = sorted([link.from_node.name, link.from_socket.identifier, link.to_node.name,
                    link.to_socket.identifier] for link in tree.links)
    return {"nodes": nodes, "links": links}


def material_tree(material):
    return material.node_tree


# --- the checks ----------------------------------------------------------------------------

def install(options, failures, seen):
    if options.addon:
        result = bpy.ops.preferences.addon_install(filepath=os.path.abspath(options.zip))
        if result == {"FINISHED"}:
            result = bpy.ops.preferences.addon_enable(module=MODULE)
    else:
        result = bpy.ops.extensions.package_install_files(
            filepath=os.path.abspath(options.zip), repo="user_default", enable_on_install=True)
    seen["install"] = sorted(result)
    if MODULE not in bpy.context.preferences.addons:
        failures.append("installing did not enable %s (%s)" % (MODULE, result))
        return False
    libraries = {library.name: library.path for library in bpy.context.preferences.filepaths.asset_libraries}
    seen["asset_library"] = libraries.get("Gloffuse")
    if seen["asset_library"] is None or not os.path.isfile(
            os.path.join(bpy.path.abspath(seen["asset_library"]), "gloffuse.blend")):
        failures.append("no asset library Gloffuse holding gloffuse.blend: %s" % libraries)
    for name, undo in (("audit_material", True), ("audit_file", True), ("fix_material", True)):
        cls = getattr(bpy.types, "GLOFFUSE_OT_" + name, None)
        if cls is None:
            failures.append("no operator gloffuse.%s" % name)
        elif undo and not {"REGISTER", "UNDO"} <= set(cls.bl_options):
            failures.append("gloffuse.%s has bl_options %s" % (name, sorted(cls.bl_options)))
    return True


def check_version_choice(failures, seen):
    """load_catalogue takes the newest entry not after this Blender, and refuses an
    add-on whose groups were built for an older masking (a catalogue written here)."""
    folder = tempfile.mkdtemp()
    entries = [{"from": [3, 4], "twin_names": "3.4's", "predictions": "3.4's"},
               {"from": [4, 0], "twin_names": "4.0's", "predictions": "4.0's"}]
    here = tuple(bpy.app.version[:2])
    for before, want in ((None, "4.0's" if here >= (4, 0) else "3.4's"),
                         ([3, 5], None if here >= (3, 5) else "3.4's")):
        with open(os.path.join(folder, "audit_catalogue.json"), "w", encoding="utf-8") as f:
            json.dump({"suits_before": before, "by_blender": entries, "rules": []}, f)
        catalogue, why_not = sys.modules[MODULE].load_catalogue(folder)
        got = None if catalogue is None else catalogue["twin_names"]
        seen.setdefault("version_choice", []).append([before, got, why_not])
        if got != want or (got is None) != (why_not is not None and "built by Blender 3.4" in why_not):
            failures.append("load_catalogue with suits_before %s: %s, %s (wanted %s)" % (before, got, why_not, want))
    shutil.rmtree(folder)


def swatches():
    """The object every material of the test library sits on, made active."""
    obj = next(o for o in bpy.data.objects if o.type == "MESH" and len(o.material_slots))
    bpy.context.view_layer.objects.active = obj
    return obj


def make_active(obj, material):
    obj.active_material_index = [slot.material for slot in obj.material_slots].index(material)


def compare(name, props, oracle, failures):
    where = "%s %s" % (oracle["file"], name)
    if props.verdict != oracle["verdict"] or props.reason != oracle["reason"]:
        failures.append("%s: panel %s (%s), audit %s (%s)" % (
            where, props.verdict, props.reason, oracle["verdict"], oracle["reason"]))
    panel = [(f.rule, json.loads(f.node_path), f.fix) for f in props.findings]
    audit = [(f["rule"], f["node_path"], f["fix"]) for f in oracle["findings"]]
    if panel != audit:
        failures.append("%s: panel findings %s, audit's %s" % (where, panel, audit))
        return
    for mine, theirs in zip(props.findings, oracle["findings"]):
        if not theirs["why"].startswith(mine.why):
            failures.append("%s: %s why %r is not the start of %r" % (where, mine.rule, mine.why, theirs["why"]))
        predicted = mine.predicted if mine.has_prediction else None
        if (predicted is None) != (theirs["predicted"] is None) or (
                predicted is not None and abs(predicted - theirs["predicted"]) > MAX_PREDICTION_ERROR):
            failures.append("%s: %s predicted %s, audit %s" % (where, mine.rule, predicted, theirs["predicted"]))
    predictions = [f["predicted"] for f in oracle["findings"] if f["predicted"] is not None]
    mean = props.mean if props.has_mean else None
    if (mean is None) != (not predictions) or (
            predictions and abs(mean - min(predictions)) > MAX_PREDICTION_ERROR):
        failures.append("%s: mean %s, the audit's darkest prediction %s" % (where, mean, predictions))


def check_audits(path, oracle, failures, seen):
    obj = swatches()
    materials = [m for m in bpy.data.materials if m.library is None and not m.is_grease_pencil]
    fresh = [m.name for m in materials if m.gloffuse.verdict != "not-judged"]
    if fresh:
        failures.append("%s: judged before any audit: %s" % (path, fresh))
    for material in materials:
        if material not in [slot.material for slot in obj.material_slots]:
            continue
        make_active(obj, material)
        if bpy.ops.gloffuse.audit_material() != {"FINISHED"}:
            failures.append("%s: audit_material did not finish" % material.name)
        compare(material.name, material.gloffuse, oracle[material.name], failures)
    bpy.ops.gloffuse.audit_file()
    for material in materials:
        if material.name not in oracle:
            failures.append("%s: %s is not in the audit's report" % (path, material.name))
            continue
        compare(material.name, material.gloffuse, oracle[material.name], failures)
    seen["verdicts"] = {m.name: m.gloffuse.verdict for m in materials}


def check_draws(path, oracle, failures, seen):
    """Each panel's draw() with a recording layout: the active material's verdict and
    findings; in the editor, a show-node button where the editor shows the node's tree."""
    obj = swatches()
    panel_types = [bpy.types.GLOFFUSE_PT_material, bpy.types.GLOFFUSE_PT_shader_editor]
    for material in [slot.material for slot in obj.material_slots if slot.material is not None]:
        make_active(obj, material)
        props = material.gloffuse
        editor = types.SimpleNamespace(type="NODE_EDITOR", tree_type="ShaderNodeTree",
                                       edit_tree=material.node_tree, id=material)
        contexts = [bpy.context, types.SimpleNamespace(space_data=editor, object=obj, material=None)]
        for panel, context in zip(panel_types, contexts):
            drawn = draw(panel, context)
            texts = labels(drawn)
            if not any(text.lower().startswith(props.verdict) for text in texts):
                failures.append("%s: %s draws no verdict %s: %s" % (material.name, panel.__name__, props.verdict, texts))
            for item in props.findings:
                for wanted in (item.rule, item.node, "Why: " + item.why, "Fix: " + item.fix):
                    if wanted not in texts:
                        failures.append("%s: %s does not draw %r" % (material.name, panel.__name__, wanted))
            shows = [e["properties"].get("node_path") for e in drawn if e.get("operator") == "gloffuse.show_node"]
            expected = [item.node_path for item in props.findings
                        if context is not bpy.context and len(json.loads(item.node_path)) == 2]
            if shows != expected:
                failures.append("%s: %s show-node buttons %s, expected %s" % (material.name, panel.__name__, shows, expected))
            nested = [item for item in props.findings if len(json.loads(item.node_path)) > 2]
            if context is not bpy.context and nested and not any(t.startswith("In ") for t in texts):
                failures.append("%s: a finding inside a group does not say where to open it" % material.name)
            for idname in ("gloffuse.audit_material", "gloffuse.fix_material", "gloffuse.audit_file"):
                if idname not in [e.get("operator") for e in drawn]:
                    failures.append("%s: %s has no %s button" % (material.name, panel.__name__, idname))
        for item in props.findings:  # a narrow sidebar wraps a long why into several labels
            recorder = Recorder()
            sys.modules[MODULE].paragraph(recorder, "Why: " + item.why, 24)
            lines = labels(recorder.drawn)
            too_long = [line for line in lines if len(line) > 24 and " " in line]
            if " ".join(lines) != "Why: " + item.why or too_long or len(lines) < 2:
                failures.append("%s: wrapped at 24 characters: %s" % (material.name, lines))
    drawn = draw(bpy.types.GLOFFUSE_PT_all_materials, bpy.context)
    listed = [e["label"] for e in drawn if "label" in e and e["label"] in oracle]
    rank = {"error": 0, "creates": 1, "loses": 2, "ok": 4}
    expected = sorted(listed, key=lambda name: (rank[oracle[name]["verdict"]], name))
    seen["all_materials"] = listed
    if listed != expected or len(listed) != len([m for m in bpy.data.materials if m.library is None]):
        failures.append("%s: All materials lists %s, failures first would be %s" % (path, listed, expected))


def rewritten_by(fix_report, path):
    return sorted(m["material"] for m in fix_report["materials"]
                  if os.path.samefile(m["file"], path) and (m.get("after") or {}).get("rewritten"))


def check_undo(path, rewritten_names, failures, seen):
    """fix_material on the first material the oracle rewrote, then Blender's undo and redo."""
    obj = swatches()
    rewritten = [bpy.data.materials[name] for name in rewritten_names]
    if not rewritten:
        return
    name = rewritten[0].name
    make_active(obj, rewritten[0])
    before = describe(rewritten[0].node_tree)
    bpy.ops.ed.undo_push(message="before the fix")
    bpy.ops.gloffuse.fix_material()
    after = describe(bpy.data.materials[name].node_tree)
    bpy.ops.ed.undo_push(message="Fix Material")  # what the UI pushes for an UNDO operator
    bpy.ops.ed.undo()
    undone = describe(bpy.data.materials[name].node_tree)
    bpy.ops.ed.redo()
    redone = describe(bpy.data.materials[name].node_tree)
    seen.setdefault("undo", {})[path] = {"material": name, "fix_changed": after != before,
                                         "undo_restored": undone == before, "redo_refixed": redone == after}
    if after == before or undone != before or redone != after:
        failures.append("%s: undo of fix_material: %s" % (path, seen["undo"][path]))


def check_fixes(path, fix_report, fixed_path, failures, seen):
    obj = swatches()
    rewritten = rewritten_by(fix_report, path)
    after = {m["material"]: m["after"] for m in fix_report["materials"] if os.path.samefile(m["file"], path)}
    fixed = []
    for material in [slot.material for slot in obj.material_slots if slot.material is not None]:
        make_active(obj, material)
        if bpy.ops.gloffuse.fix_material() == {"FINISHED"}:
            fixed.append(material.name)
        if material.gloffuse.verdict != after[material.name]["verdict"]:
            failures.append("%s: %s is %s after fix_material (%s), %s after audit --fix" % (
                path, material.name, material.gloffuse.verdict, material.gloffuse.reason,
                after[material.name]["verdict"]))
    already = [name for name in rewritten if name not in fixed
               and seen.get("undo", {}).get(path, {}).get("material") == name]
    seen.setdefault("fixed", {})[path] = sorted(fixed)
    if sorted(fixed + already) != rewritten:
        failures.append("%s: fix_material fixed %s, audit --fix rewrote %s" % (path, sorted(fixed), rewritten))
    mine = {m.name: describe(m.node_tree) for m in bpy.data.materials
            if m.library is None and m.node_tree is not None}
    with bpy.data.libraries.load(fixed_path, link=False) as (source, target):
        target.materials = [name for name in source.materials if name in mine]
    for material in target.materials:
        theirs = describe(material.node_tree)
        if mine[plain(material.name)] != theirs:
            failures.append("%s: %s differs from audit --fix's copy:\n  panel %s\n  audit %s" % (
                path, plain(material.name), mine[plain(material.name)], theirs))


def check(options, seen):
    failures = []
    if not install(options, failures, seen):
        return failures
    check_version_choice(failures, seen)
    with open(options.oracle, encoding="utf-8") as f:
        report = json.load(f)
    with open(options.fix_report, encoding="utf-8") as f:
        fix_report = json.load(f)
    for path in options.files:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(path), load_ui=False)
        oracle = {m["material"]: m for m in report["materials"]
                  if os.path.samefile(m["file"], path)}
        check_audits(path, oracle, failures, seen)
        check_draws(path, oracle, failures, seen)
        rewritten = rewritten_by(fix_report, path)
        check_undo(path, rewritten, failures, seen)
        check_fixes(path, fix_report, os.path.join(options.fixed_dir, os.path.basename(path)), failures, seen)
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
