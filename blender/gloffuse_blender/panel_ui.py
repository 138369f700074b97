# ---------------------------------------------------------------------------
# gloffuse panel_ui.py: the audit inside Blender (issue 42). Each material's
# result in `material.gloffuse` (verdict, mean, reason, findings), the
# operators gloffuse.audit_material, gloffuse.audit_file, gloffuse.fix_material
# and gloffuse.show_node, a "Gloffuse" panel in Properties > Material and a
# "Gloffuse" tab in the Shader Editor's sidebar (the active material, and every
# material of the file, failures first). The verdicts are panel_verdict.py's.
#
# A module of the gloffuse_blender package, bundled into the extension's
# __init__.py by the gloffuse binary; addon.py calls register_panel and
# unregister_panel.
#
#   register_panel(directory) / unregister_panel()
#   draw_material(layout, material, editor_tree), draw_all_materials(layout)
# ---------------------------------------------------------------------------
import json
import os
import textwrap

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from .audit_rules import resolve_path
from .compat import material_node_tree
from .panel_verdict import FAILING, VERDICT_RANK, audit_one, fix_one, load_catalogue

VERDICTS = (
    ("not-judged", "Not judged", "Not audited yet"),
    ("ok", "OK", "No rule fired beyond the tolerance"),
    ("loses", "Loses", "Loses energy a conserving twin keeps"),
    ("creates", "Creates", "Reflects more light than it receives"),
    ("error", "Error", "Cannot be audited as authored"),
)
VERDICT_ICONS = {"not-judged": "QUESTION", "ok": "CHECKMARK", "loses": "ERROR",
                 "creates": "ERROR", "error": "CANCEL"}
# Where the add-on found its catalogue and library (set by register_panel).
PANEL_STATE = {"directory": None, "catalogue": None, "why_not": None, "loaded": False}


class GloffuseFinding(bpy.types.PropertyGroup):
    rule: StringProperty(name="Rule")
    node: StringProperty(name="Node", description="The node's path: material, group nodes, node")
    node_path: StringProperty(name="Node path (JSON)", options={"HIDDEN"})
    node_type: StringProperty(name="Node type")
    effect: StringProperty(name="Effect")
    why: StringProperty(name="Why")
    fix: StringProperty(name="Fix")
    predicted: FloatProperty(name="Predicted", description="The lobe's predicted brightness (1.0 = 100 %)")
    has_prediction: BoolProperty(name="Has a prediction")
    twin: StringProperty(name="Twin")


class GloffuseResult(bpy.types.PropertyGroup):
    verdict: EnumProperty(name="Verdict", items=VERDICTS, default="not-judged")
    reason: StringProperty(name="Reason")
    mean: FloatProperty(name="Mean", default=1.0,
                        description="Predicted brightness (1.0 = 100 %): the darkest flagged lobe's")
    has_mean: BoolProperty(name="Has a mean", description="Whether a finding predicts the mean")
    replaced: IntProperty(name="Replaced", description="How many lobes a fix replaces")
    refusal: StringProperty(name="No fix", description="Why a fix leaves the material alone")
    findings: CollectionProperty(type=GloffuseFinding)


def catalogue():
    """The add-on's catalogue, read once; None when it has none for this Blender
    (PANEL_STATE["why_not"] says why)."""
    if not PANEL_STATE["loaded"]:
        PANEL_STATE["catalogue"], PANEL_STATE["why_not"] = load_catalogue(PANEL_STATE["directory"])
        PANEL_STATE["loaded"] = True
    return PANEL_STATE["catalogue"]


def library_blend():
    return os.path.join(PANEL_STATE["directory"], "library", "gloffuse.blend")


def store(material, result):
    """Write an audit's result into material.gloffuse."""
    props = material.gloffuse
    props.verdict = result["verdict"]
    props.reason = result["reason"]
    props.has_mean = result["mean"] is not None
    props.mean = result["mean"] if result["mean"] is not None else 1.0
    props.replaced = result["replaced"]
    props.refusal = ""
    props.findings.clear()
    for item in result["findings"]:
        row = props.findings.add()
        row.rule = item["rule"]
        row.node = " \u25b8 ".join(item["node"])
        row.node_path = json.dumps(item["node"])
        row.node_type = item["node_type"]
        row.effect = item["effect"]
        row.why = item["why"]
        row.fix = item["fix"]
        row.has_prediction = item["predicted"] is not None
        row.predicted = item["predicted"] if item["predicted"] is not None else 0.0
        row.twin = item["twin"] or ""


def audit_and_store(material):
    result = audit_one(catalogue(), material)
    store(material, result)
    return result


def context_material(context):
    """The material a panel or operator is about: the Properties editor's, the
    Shader Editor's, else the active object's."""
    material = getattr(context, "material", None)
    space = getattr(context, "space_data", None)
    if material is None and isinstance(getattr(space, "id", None), bpy.types.Material):
        material = space.id
    if material is None and getattr(context, "object", None) is not None:
        material = context.object.active_material
    return material


def audited_materials():
    """The file's materials that can carry a result (no Grease Pencil one, none
    linked: a library's data cannot be written)."""
    return [m for m in bpy.data.materials if not m.is_grease_pencil and m.library is None]


# --- operators ---------------------------------------------------------------------

def active_material_is_local(context):
    """The panel has its catalogue and an active material of this file (a
    library's cannot be written): what the operators on one material need."""
    material = context_material(context)
    return catalogue() is not None and material is not None and material.library is None


class GLOFFUSE_OT_audit_material(bpy.types.Operator):
    """Audit the active material without rendering: its verdict, predicted brightness and findings"""
    bl_idname = "gloffuse.audit_material"
    bl_label = "Audit Material"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return active_material_is_local(context)

    def execute(self, context):
        result = audit_and_store(context_material(context))
        self.report({"INFO"}, "%s: %s" % (result["verdict"], result["reason"]))
        return {"FINISHED"}


class GLOFFUSE_OT_audit_file(bpy.types.Operator):
    """Audit every material of the file without rendering"""
    bl_idname = "gloffuse.audit_file"
    bl_label = "Audit All Materials"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return catalogue() is not None

    def execute(self, context):
        verdicts = [audit_and_store(material)["verdict"] for material in audited_materials()]
        failing = sum(1 for verdict in verdicts if verdict in FAILING + ("error",))
        self.report({"INFO"}, "%d materials audited, %d failing" % (len(verdicts), failing))
        return {"FINISHED"}


class GLOFFUSE_OT_fix_material(bpy.types.Operator):
    """Replace the active material's flagged lobes by their conserving twins (the replacements gloffuse audit --fix makes)"""
    bl_idname = "gloffuse.fix_material"
    bl_label = "Fix Material"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return active_material_is_local(context)

    def execute(self, context):
        material = context_material(context)
        replaced, refusal = fix_one(catalogue(), material, library_blend())
        result = audit_and_store(material)
        material.gloffuse.refusal = refusal or ""
        if refusal is not None:
            self.report({"WARNING"}, "%s: %s" % (material.name, refusal))
            return {"CANCELLED"}
        self.report({"INFO"}, "%s: %d replaced, now %s" % (material.name, replaced, result["verdict"]))
        return {"FINISHED"}


def node_editor_tree(context):
    """The tree the Shader Editor shows (a group's, when one is open), or None."""
    space = getattr(context, "space_data", None)
    if getattr(space, "type", None) != "NODE_EDITOR":
        return None
    return getattr(space, "edit_tree", None)


def finding_tree(material, path):
    """(tree holding the finding's node, node) along `path`, or (None, None)."""
    tree = material_node_tree(material)
    if tree is None or len(path) < 2:
        return None, None
    node, chain = resolve_path(tree, path)
    holder = chain[-1].node_tree if chain else tree
    return (holder, node) if node is not None else (None, None)


class GLOFFUSE_OT_show_node(bpy.types.Operator):
    """Select and frame the finding's node in this Shader Editor"""
    bl_idname = "gloffuse.show_node"
    bl_label = "Show Node"
    bl_options = {"REGISTER"}

    node_path: StringProperty(name="Node path (JSON)", options={"HIDDEN", "SKIP_SAVE"})

    def execute(self, context):
        material = context_material(context)
        holder, node = finding_tree(material, json.loads(self.node_path or "[]"))
        if node is None:
            self.report({"WARNING"}, "the node is gone: audit the material again")
            return {"CANCELLED"}
        if holder != node_editor_tree(context):
            self.report({"WARNING"}, "the node is in %s: open it in the Shader Editor" % holder.name)
            return {"CANCELLED"}
        for other in holder.nodes:
            other.select = False
        node.select = True
        holder.nodes.active = node
        bpy.ops.node.view_selected()
        return {"FINISHED"}


# --- panels ------------------------------------------------------------------------

def text_columns(context):
    """How many characters of UI text fit across the panel's region, or None (no
    region: a draw outside a window) for no wrapping."""
    region = getattr(context, "region", None)
    if region is None or region.width <= 0:
        return None
    # ~7 px a character at scale 1, less the panel's and box's margins.
    return max(16, int(region.width / (7.0 * bpy.context.preferences.system.ui_scale)) - 4)


def paragraph(layout, text, columns, icon="NONE"):
    """`text` as labels of at most `columns` characters (Blender's labels do not
    wrap, and a narrow sidebar would cut a finding's why and fix short)."""
    # A word longer than a line stays whole (Blender cuts it), so the lines put
    # together are the text.
    lines = textwrap.wrap(text, columns, break_long_words=False, break_on_hyphens=False) \
        if columns else [text]
    for n, line in enumerate(lines or [""]):
        layout.label(text=line, icon=icon if n == 0 else "NONE")


def verdict_label(props):
    text = dict((key, name) for key, name, _ in VERDICTS)[props.verdict]
    if props.has_mean:
        text += " \u2014 predicted %.1f %%" % (100.0 * props.mean)
    return text


def draw_finding(layout, material, item, editor_tree, columns):
    box = layout.box()
    row = box.row()
    row.label(text=item.rule, icon="ERROR" if item.effect in FAILING + ("error",) else "INFO")
    holder, _ = finding_tree(material, json.loads(item.node_path or "[]"))
    if editor_tree is not None and holder is not None and holder == editor_tree:
        op = row.operator("gloffuse.show_node", text="", icon="ZOOM_SELECTED")
        op.node_path = item.node_path
    column = box.column(align=True)
    paragraph(column, item.node, columns)
    if editor_tree is not None and holder is not None and holder != editor_tree:
        paragraph(column, "In %s: open it to show the node" % holder.name, columns, icon="NODETREE")
    if item.has_prediction:
        column.label(text="Predicted %.1f %% for this lobe" % (100.0 * item.predicted))
    paragraph(column, "Why: " + item.why, columns)
    paragraph(column, "Fix: " + item.fix, columns)


def draw_material(layout, material, editor_tree, columns=None):
    """The material's verdict, mean, findings and the operators' buttons, the
    long texts wrapped at `columns` characters (None: not wrapped)."""
    if catalogue() is None:
        paragraph(layout, PANEL_STATE["why_not"], columns, icon="ERROR")
        return
    if material is None:
        layout.label(text="No active material")
        return
    props = material.gloffuse
    layout.label(text=verdict_label(props), icon=VERDICT_ICONS[props.verdict])
    if props.reason:
        paragraph(layout, props.reason, columns)
    row = layout.row(align=True)
    row.operator("gloffuse.audit_material", icon="VIEWZOOM")
    row.operator("gloffuse.fix_material", icon="MODIFIER")
    layout.operator("gloffuse.audit_file", icon="MATERIAL")
    if props.refusal:
        paragraph(layout, "No fix: " + props.refusal, columns, icon="INFO")
    for item in props.findings:
        draw_finding(layout, material, item, editor_tree, columns)


def draw_all_materials(layout):
    """Every material of the file with its verdict, failures first."""
    materials = sorted(audited_materials(), key=lambda m: (VERDICT_RANK[m.gloffuse.verdict], m.name))
    if not materials:
        layout.label(text="No materials")
    for material in materials:
        row = layout.split(factor=0.55)
        row.label(text=material.name, icon=VERDICT_ICONS[material.gloffuse.verdict])
        row.label(text=verdict_label(material.gloffuse))
    layout.operator("gloffuse.audit_file", icon="MATERIAL")


class GLOFFUSE_PT_material(bpy.types.Panel):
    bl_label = "Gloffuse"
    bl_idname = "GLOFFUSE_PT_material"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        return context_material(context) is not None

    def draw(self, context):
        draw_material(self.layout, context_material(context), None, text_columns(context))


class ShaderEditorTab:
    """The Shader Editor sidebar's Gloffuse tab (a mix-in of its panels)."""
    bl_space_type = "NODE_EDITOR"
    bl_region_type = "UI"
    bl_category = "Gloffuse"

    @classmethod
    def poll(cls, context):
        return getattr(context.space_data, "tree_type", None) == "ShaderNodeTree"


class GLOFFUSE_PT_shader_editor(ShaderEditorTab, bpy.types.Panel):
    bl_label = "Active Material"
    bl_idname = "GLOFFUSE_PT_shader_editor"

    def draw(self, context):
        draw_material(self.layout, context_material(context), node_editor_tree(context),
                      text_columns(context))


class GLOFFUSE_PT_all_materials(ShaderEditorTab, bpy.types.Panel):
    bl_label = "All Materials"
    bl_idname = "GLOFFUSE_PT_all_materials"

    def draw(self, context):
        draw_all_materials(self.layout)


PANEL_CLASSES = (GloffuseFinding, GloffuseResult, GLOFFUSE_OT_audit_material, GLOFFUSE_OT_audit_file,
                 GLOFFUSE_OT_fix_material, GLOFFUSE_OT_show_node, GLOFFUSE_PT_material,
                 GLOFFUSE_PT_shader_editor, GLOFFUSE_PT_all_materials)


def register_panel(directory):
    """Register the classes and material.gloffuse; `directory` holds the catalogue
    and the library (the extension's own folder)."""
    PANEL_STATE.update(directory=directory, catalogue=None, loaded=False)
    for cls in PANEL_CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Material.gloffuse = PointerProperty(type=GloffuseResult)


def unregister_panel():
    del bpy.types.Material.gloffuse
    for cls in reversed(PANEL_CLASSES):
        bpy.utils.unregister_class(cls)
