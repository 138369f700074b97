# ---------------------------------------------------------------------------
# gloffuse params.py: checks the parameter document (GLOFFUSE_PARAMS) before
# anything is built, and says what is wrong with it.
#
# A module of the gloffuse_blender package. Functions and constants only; uses
# max_name_bytes() and masking_family() from compat.py, check_fields() from
# contract.py.
#
#   load_params(text) -> dict          parse the parameter JSON, check its fields
#                                      against the contract, and resolve it
#   resolve_params(document) -> params the document as the builders read it:
#                                      each group with the fields of the masking
#                                      family of the Blender this runs in
#   validate_params(params) -> params  raise ValueError saying what is wrong
# ---------------------------------------------------------------------------
import json
import math

from .compat import blender_at_least, masking_family, max_name_bytes
from .contract import check_fields

DISTRIBUTIONS = ("BECKMANN", "GGX", "ASHIKHMIN_SHIRLEY")
CURVE_VARIABLES = ("roughness", "alpha")
MASKINGS = ("separable", "height-correlated")
COLOR_MODELS = ("exact", "physical")
ENGINES = ("cycles", "eevee")
VIEW_GROUPS = ("correction_group", "shader_group", "multiscatter_group")


def finite_list(value, what):
    """value as a list of floats; ValueError unless it is a non-empty list of
    finite numbers (booleans are not numbers here)."""
    if not isinstance(value, list) or not value:
        raise ValueError("%s must be a non-empty list of numbers" % what)
    out = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, (int, float)) \
                or not math.isfinite(float(item)):
            raise ValueError("%s holds %r, which is not a finite number" % (what, item))
        out.append(float(item))
    return out


def _name(value, where, limit, seen=None):
    """A node-group or image name: a non-empty string within Blender's limit,
    and (with `seen`) not used twice."""
    if not isinstance(value, str) or not value.strip():
        raise ValueError("%s must be a non-empty string" % where)
    if len(value.encode("utf-8")) > limit:
        raise ValueError("%s %r is longer than Blender's %d-byte name limit"
                         % (where, value, limit))
    if seen is not None:
        if value in seen:
            raise ValueError("%s %r is used twice" % (where, value))
        seen.add(value)


def resolve_params(document):
    """The parameter document as the builders read it. The document carries,
    per group, one entry in "families" per masking family; this picks the one
    of the Blender the script runs in (or the only one there is) and copies its
    curve, description, coefficients source, image and table into the group."""
    if not isinstance(document, dict):
        raise ValueError("the parameter document must be a JSON object")
    first = document.get("height_correlated_from")
    if not (isinstance(first, list) and len(first) == 2
            and all(isinstance(v, int) and not isinstance(v, bool) for v in first)):
        raise ValueError("height_correlated_from must be [major, minor], got %r" % (first,))
    masking = masking_family(first)
    groups = document.get("groups")
    if not isinstance(groups, list) or not groups:
        raise ValueError("the parameter document needs a non-empty 'groups' list")
    resolved = []
    for index, spec in enumerate(groups):
        where = "groups[%d]" % index
        if not isinstance(spec, dict):
            raise ValueError("%s must be an object" % where)
        families = spec.get("families")
        if not isinstance(families, list) or not families \
                or not all(isinstance(f, dict) for f in families):
            raise ValueError("%s.families must be a non-empty list of objects" % where)
        for family in families:
            if family.get("masking") not in MASKINGS:
                raise ValueError("%s.families: masking %r is not one of %s"
                                 % (where, family.get("masking"), ", ".join(MASKINGS)))
        chosen = [f for f in families if f["masking"] == masking] or families
        if len(chosen) != 1:
            raise ValueError("%s.families holds %d entries for %s masking; expected one"
                             % (where, len(chosen), masking))
        family = chosen[0]
        group = {key: value for key, value in spec.items() if key != "families"}
        for key in ("masking", "curve", "description", "coefficients_source"):
            group[key] = family.get(key)
        if isinstance(spec.get("view"), dict):
            view = dict(spec["view"])
            view["image"] = family.get("image")
            view["table"] = family.get("table")
            group["view"] = view
        if spec.get("layered_group") is not None:
            group["layered"] = {
                "shader_group": spec["layered_group"],
                "image": family.get("image"), "table": family.get("table"),
                "coat_image": family.get("coat_image"), "coat_table": family.get("coat_table"),
                "coat_gain_image": family.get("coat_gain_image"),
            }
        # The anisotropic group is built where this Blender's family carries its table
        # (not Beckmann in 3.0-3.4, which sample the wrong lobe for it).
        if spec.get("anisotropic_group") is not None and family.get("anisotropic_table") is not None:
            group["anisotropic"] = {
                "shader_group": spec["anisotropic_group"],
                "image": family.get("anisotropic_image"),
                "table": family.get("anisotropic_table"),
            }
        # The glass groups are built where this Blender renders the glass of its family's
        # table (not 3.5, whose glass is still 3.0-3.4's).
        glass_table = family.get("glass_table")
        if spec.get("glass_group") is not None and isinstance(glass_table, dict) \
                and _version_pair(glass_table.get("from_version"), where) \
                and blender_at_least(glass_table["from_version"]):
            group["glass"] = {
                "glass_group": spec["glass_group"],
                "refraction_group": spec.get("refraction_group"),
                "image": family.get("glass_image"),
                "table": glass_table,
            }
        resolved.append(group)
    params = {key: value for key, value in document.items() if key != "groups"}
    params["groups"] = resolved
    return validate_params(params)


def _version_pair(value, where):
    """True for [major, minor]; ValueError otherwise."""
    if isinstance(value, list) and len(value) == 2 \
            and all(isinstance(v, int) and not isinstance(v, bool) for v in value):
        return True
    raise ValueError("%s: glass_table.from_version must be [major, minor], got %r" % (where, value))


def _table_sizes(table, keys, what):
    """ValueError unless `table` is an object whose `keys` are integers of at least 2."""
    if not isinstance(table, dict) or not all(
            isinstance(table.get(k), int) and table.get(k) >= 2 for k in keys):
        raise ValueError(what)


def _check_view(view, where, limit, seen):
    if not isinstance(view, dict):
        raise ValueError("%s.view must be an object" % where)
    present = [key for key in VIEW_GROUPS if view.get(key) is not None]
    if not present:
        raise ValueError("%s.view names none of %s" % (where, ", ".join(VIEW_GROUPS)))
    for key in present:
        _name(view[key], "%s.view.%s" % (where, key), limit, seen)
    _name(view.get("image"), "%s.view.image" % where, limit)
    _table_sizes(view.get("table"), ("width", "height"),
                 "%s.view.table needs integer width and height of at least 2" % where)


def _check_layered(layered, where, limit, seen):
    if not isinstance(layered, dict):
        raise ValueError("%s.layered must be an object" % where)
    _name(layered.get("shader_group"), "%s.layered.shader_group" % where, limit, seen)
    for key in ("image", "coat_image"):
        _name(layered.get(key), "%s.layered.%s" % (where, key), limit)
    coat = layered.get("coat_table")
    if layered.get("coat_gain_image") is not None:
        _name(layered["coat_gain_image"], "%s.layered.coat_gain_image" % where, limit)
        if not isinstance(coat, dict) or "gain" not in coat:
            raise ValueError("%s.layered.coat_gain_image needs coat_table.gain" % where)
    _table_sizes(coat, ("size", "slices"),
                 "%s.layered.coat_table needs integer size and slices of at least 2" % where)
    if finite_list([coat.get("ior_max")], "%s.layered.coat_table.ior_max" % where)[0] <= 1.0:
        raise ValueError("%s.layered.coat_table.ior_max must be above 1" % where)


def _check_anisotropic(anisotropic, where, limit, seen):
    if not isinstance(anisotropic, dict):
        raise ValueError("%s.anisotropic must be an object" % where)
    _name(anisotropic.get("shader_group"), "%s.anisotropic.shader_group" % where, limit, seen)
    _name(anisotropic.get("image"), "%s.anisotropic.image" % where, limit)
    _table_sizes(anisotropic.get("table"), ("size", "azimuths"),
                 "%s.anisotropic.table needs integer size and azimuths of at least 2" % where)


def _check_glass(glass, where, limit, seen):
    if not isinstance(glass, dict):
        raise ValueError("%s.glass must be an object" % where)
    for key in ("glass_group", "refraction_group"):
        _name(glass.get(key), "%s.glass.%s" % (where, key), limit, seen)
    _name(glass.get("image"), "%s.glass.image" % where, limit)
    table = glass.get("table")
    _table_sizes(table, ("size", "slices"),
                 "%s.glass.table needs integer size and slices of at least 2" % where)
    if finite_list([table.get("ior_max")], "%s.glass.table.ior_max" % where)[0] <= 1.0:
        raise ValueError("%s.glass.table.ior_max must be above 1" % where)
    if table.get("glass_group") not in ("gain", "multiscatter"):
        raise ValueError("%s.glass.table.glass_group is %r; expected 'gain' or "
                         "'multiscatter'" % (where, table.get("glass_group")))


def _check_curve(curve, where):
    if not isinstance(curve, dict):
        raise ValueError("%s.curve must be an object" % where)
    if curve.get("variable") not in CURVE_VARIABLES:
        raise ValueError("%s.curve.variable is %r; expected 'roughness' or 'alpha'"
                         % (where, curve.get("variable")))
    for key in ("numerator", "denominator"):
        coeffs = finite_list(curve.get(key), "%s.curve.%s" % (where, key))
        if not any(coeffs):
            raise ValueError("%s.curve.%s is identically zero" % (where, key))


# What each mode adds to a group, and the check of it.
_MODE_CHECKS = (("view", _check_view), ("layered", _check_layered),
                ("anisotropic", _check_anisotropic), ("glass", _check_glass))


def _check_group(spec, where, limit, seen, normals):
    if not isinstance(spec, dict):
        raise ValueError("%s must be an object" % where)
    if spec.get("distribution") not in DISTRIBUTIONS:
        raise ValueError("%s.distribution is %r; expected one of %s"
                         % (where, spec.get("distribution"), ", ".join(DISTRIBUTIONS)))
    for key in ("correction_group", "shader_group"):
        _name(spec.get(key), "%s.%s" % (where, key), limit, seen)
    if spec.get("engine", "cycles") not in ENGINES:
        raise ValueError("%s.engine is %r; expected one of %s"
                         % (where, spec.get("engine"), ", ".join(ENGINES)))
    if any(spec.get(mode) is not None for mode, _ in _MODE_CHECKS) \
            and spec.get("normal_group") not in normals:
        # One normal group serves every spec of an engine.
        _name(spec.get("normal_group"), "%s.normal_group" % where, limit, seen)
        normals.add(spec["normal_group"])
    for mode, check in _MODE_CHECKS:
        if spec.get(mode) is not None:
            check(spec[mode], where, limit, seen)
    for key in ("description", "coefficients_source"):
        if not isinstance(spec.get(key, ""), str):
            raise ValueError("%s.%s must be a string" % (where, key))
    _check_curve(spec.get("curve"), where)


def validate_params(params):
    """Check the resolved parameters; raise ValueError saying what is wrong."""
    if not isinstance(params, dict):
        raise ValueError("the parameter document must be a JSON object")
    if params.get("color_model", "exact") not in COLOR_MODELS:
        raise ValueError("color_model is %r; expected one of %s"
                         % (params.get("color_model"), ", ".join(COLOR_MODELS)))
    groups = params.get("groups")
    if not isinstance(groups, list) or not groups:
        raise ValueError("the parameter document needs a non-empty 'groups' list")
    limit = max_name_bytes()
    seen = set()
    normals = set()
    for index, spec in enumerate(groups):
        _check_group(spec, "groups[%d]" % index, limit, seen, normals)
    return params


def load_params(text):
    """Parse the generate job's JSON parameter document, check its fields, and
    resolve it for this Blender."""
    return resolve_params(check_fields(json.loads(text), "generate_document"))
