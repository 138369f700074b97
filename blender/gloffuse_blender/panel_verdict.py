# ---------------------------------------------------------------------------
# gloffuse panel_verdict.py: the audit's verdict without a render, inside
# Blender (the extension's panel and operators, issue 42). The rules are the
# audit's own (audit_rules.scan_material), the fixes its own
# (audit_twin.apply_finding); the words, version ranges, twin names and
# predictions come from the catalogue Rust writes into the extension
# (crates/gloffuse/src/audit/catalogue.rs, audit_catalogue.json). What is
# mirrored here, and guarded by tests/blender_panel.rs against `gloffuse
# audit --no-render --json` on the same file:
#   predict(): Predictor::compute's checks (rules.rs), and a linear
#     interpolation of the catalogue's grid of the predictor's own values;
#   judge(): judge.rs's verdict without a render (verdict, by_rules);
#   fix_refusal(): fix_choice.rs's choice without a render (choose,
#     in_a_library, no_safe_twin's first words).
# A module of the gloffuse_blender package, bundled into the extension's
# __init__.py by the gloffuse binary. Functions and constants only.
#
#   load_catalogue(directory) -> (the catalogue (dict), None) or (None, why not)
#   audit_one(catalogue, material) -> {verdict, reason, mean, findings, error, replaced}
#   fix_one(catalogue, material, library_blend) -> (replaced, refusal or None)
# ---------------------------------------------------------------------------
import json
import math
import os

import bpy

from .audit_rules import MULTISCATTER_TWIN, TWIN_KINDS, applicable_rules, scan_material, twin_groups
from .audit_twin import apply_finding, has_replacement
from .compat import blender_at_least, material_node_tree

CATALOGUE_FILE = "audit_catalogue.json"
PATH_SEPARATOR = " \u25b8 "  # "A ▸ B", as the audit's reports join a node's path
FAILING = ("loses", "creates")
# The panel's order of verdicts: failures first.
VERDICT_RANK = {"error": 0, "creates": 1, "loses": 2, "not-judged": 3, "ok": 4}


NO_CATALOGUE = "This add-on holds no audit catalogue: build it with gloffuse generate " \
    "--extension (or --addon)"
UNSUITED = "This add-on's groups were built by Blender %s for its Cycles, which renders " \
    "them wrongly here: build it in this Blender (gloffuse generate --addon FILE.zip " \
    "--blender ...)"


def load_catalogue(directory):
    """(the catalogue beside the add-on as this Blender reads it, None), or (None, why
    the add-on has no audit here). This Blender reads the twins' names and predictions
    of the newest `by_blender` entry not after it. None: an add-on built without it (by
    gloffuse's library, not its command line), or whose groups do not suit this
    Blender (`suits_before`)."""
    path = os.path.join(directory, CATALOGUE_FILE)
    if not os.path.isfile(path):
        return None, NO_CATALOGUE
    with open(path, encoding="utf-8") as f:
        catalogue = json.load(f)
    mine = [entry for entry in catalogue["by_blender"] if blender_at_least(entry["from"])]
    before = catalogue.get("suits_before")
    if not mine or (before is not None and blender_at_least(before)):
        built = catalogue["by_blender"][0]["from"]
        return None, UNSUITED % ".".join(str(part) for part in built)
    chosen = mine[-1]
    return dict(catalogue, twin_names=chosen["twin_names"], predictions=chosen["predictions"]), None


def catalogue_rule(catalogue, rule_id):
    return next((rule for rule in catalogue["rules"] if rule["id"] == rule_id), None)


def effect_of(catalogue, rule_id):
    """The rule's effect; a rule the catalogue lacks counts as info (judge.rs's word)."""
    rule = catalogue_rule(catalogue, rule_id)
    return rule["effect"] if rule is not None else "info"


# --- predictions: the catalogue's grid, interpolated ---------------------------------

def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def grid_position(points, x):
    """(i, t): x lies at points[i] + t (points[i + 1] - points[i]), evenly spaced points."""
    steps = len(points) - 1
    at = (x - points[0]) / (points[-1] - points[0]) * steps
    i = min(int(math.floor(at)), steps - 1)
    return i, at - i


def mix(a, b, t):
    if a is None or b is None:
        return None  # a grid point the predictor does not model
    return a * (1.0 - t) + b * t


def predict(catalogue, rule, detail):
    """What Predictor::compute (rules.rs) gives for a finding, looked up: None
    where a value is linked, the lobe anisotropic or not modelled."""
    table = catalogue["predictions"]
    distribution = str(detail.get("distribution") or "").upper().replace("-", "_")
    roughness = detail.get("roughness")
    if distribution not in table["glossy"] or not is_number(roughness) or not 0.0 <= roughness <= 1.0:
        return None
    if "anisotropy" in detail and detail["anisotropy"] != 0.0:
        return None
    i, t = grid_position(table["roughness"], roughness)
    if rule == "glossy-single-scatter":
        row = table["glossy"][distribution]
        return mix(row[i], row[i + 1], t)
    if rule == "mix-fresnel-layering":
        ior = detail.get("ior")
        if not is_number(ior) or not 1.0 <= ior <= 3.0:
            return None
        j, u = grid_position(table["ior"], ior)
        rows = table["layering"][distribution]
        return mix(mix(rows[i][j], rows[i][j + 1], u), mix(rows[i + 1][j], rows[i + 1][j + 1], u), t)
    return None


# --- the verdict -----------------------------------------------------------------------

def node_words(item):
    return PATH_SEPARATOR.join(item["node"])


def judge(catalogue, findings, error):
    """(verdict, reason) as judge.rs gives them without a render."""
    if error is not None:
        return "error", error
    for item in findings:
        if effect_of(catalogue, item["rule"]) == "error":
            return "error", "%s (%s)" % (item["rule"], node_words(item))
    for item in findings:
        if effect_of(catalogue, item["rule"]) == "creates":
            return "creates", "%s at %s" % (item["rule"], node_words(item))
    for item in findings:
        predicted = item.get("predicted")
        if effect_of(catalogue, item["rule"]) == "loses" \
                and (predicted is None or 1.0 - predicted > catalogue["tolerance"]):
            return "loses", "%s at %s" % (item["rule"], node_words(item))
    return "ok", "no rule fired beyond the tolerance (not rendered)"


def audit_one(catalogue, material):
    """The material's findings (the audit's rules, worded from the catalogue), verdict,
    predicted mean (the darkest lobe's prediction; None: no finding predicts one), and
    how many lobes a fix replaces."""
    rules = applicable_rules(catalogue["rules"])
    try:
        findings, error = scan_material(material, rules, twin_groups(catalogue))
    except Exception as failure:  # as audit_job.scan_file: the material's own error
        findings, error = [], "scan failed: %s: %s" % (type(failure).__name__, failure)
    for item in findings:
        rule = catalogue_rule(catalogue, item["rule"]) or {}
        item["why"] = rule.get("why", "a rule this gloffuse does not know")
        item["fix"] = rule.get("fix", "")
        item["effect"] = effect_of(catalogue, item["rule"])
        item["predicted"] = predict(catalogue, item["rule"], item["detail"])
    verdict, reason = judge(catalogue, findings, error)
    predicted = [item["predicted"] for item in findings if item["predicted"] is not None]
    return {"verdict": verdict, "reason": reason, "findings": findings, "error": error,
            "mean": min(predicted) if predicted else None,
            "replaced": sum(1 for item in findings if has_replacement(item))}


# --- the fix ---------------------------------------------------------------------------

def fix_refusal(result, material):
    """Why `gloffuse audit --fix --no-render` would leave the material alone, or None
    (fix_choice.rs: only a failing verdict, nothing inside a library, a replacement)."""
    if result["verdict"] not in FAILING:
        return "its verdict is %s: nothing to fix" % result["verdict"]
    findings = result["findings"]
    failing = [item for item in findings if item["effect"] in FAILING]
    for item in failing:
        for linked in findings:
            if linked["rule"] == "linked-library" and item["node"][:len(linked["node"])] == linked["node"]:
                return "no safe fix for %s at %s: it is linked from %s, so fix that file" % (
                    item["rule"], node_words(item), linked["detail"].get("library") or "its library")
    if material.library is not None:
        return "it is linked from %s, so fix that file" % material.library.filepath
    if result["replaced"] == 0:
        what = " for %s at %s" % (failing[0]["rule"], node_words(failing[0])) if failing else ""
        if failing and failing[0]["rule"] == "add-reflecting":
            return "no safe fix%s: the share of the Add Shader to take away is measured by the " \
                "furnace render (gloffuse audit --fix)" % what
        return "no safe fix%s: no conserving replacement exists in this Blender" % what
    return None


# The generate modes whose groups the twins use (the extension needs them all for every fix).
TWIN_MODES = sorted(set(TWIN_KINDS.values()))


def twin_group_names(catalogue):
    return {name for names in catalogue["twin_names"].values() for name in names.values()}


def missing_twin_groups(catalogue, findings):
    """The gloffuse groups the replacements use that the file still lacks (the
    extension was built without their mode), sorted."""
    groups = twin_group_names(catalogue) - {MULTISCATTER_TWIN}
    return sorted({name for item in findings if has_replacement(item)
                   for name in (item["twin"], item.get("metal_twin"))
                   if name in groups and name not in bpy.data.node_groups})


def bring_twin_groups(catalogue, findings, library_blend):
    """Append from the extension's library the gloffuse groups the replacements use
    that the file lacks (the command line builds them; the extension ships them)."""
    wanted = {name for item in findings for name in (item["twin"], item.get("metal_twin"))
              if name in twin_group_names(catalogue) and name not in bpy.data.node_groups}
    if not wanted or not os.path.isfile(library_blend):
        return
    with bpy.data.libraries.load(library_blend, link=False) as (source_data, target_data):
        target_data.node_groups = [name for name in source_data.node_groups if name in wanted]


def fix_one(catalogue, material, library_blend):
    """Apply to the material's real tree the replacements `gloffuse audit --fix
    --no-render` makes (audit_twin.apply_finding, in the findings' order). Returns
    (how many were applied, why not or None)."""
    result = audit_one(catalogue, material)
    refusal = fix_refusal(result, material)
    tree = material_node_tree(material)
    if refusal is None and tree is None:
        refusal = "it has no node tree"
    if refusal is not None:
        return 0, refusal
    findings = [dict(item, scale=None) for item in result["findings"]]
    bring_twin_groups(catalogue, findings, library_blend)
    missing = missing_twin_groups(catalogue, findings)
    if missing:
        return 0, "the extension carries no %s: build it with gloffuse generate --extension " \
            "--mode %s" % (", ".join(missing), ",".join(TWIN_MODES))
    return sum(1 for item in findings if apply_finding(tree, item)), None
