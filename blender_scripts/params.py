# ---------------------------------------------------------------------------
# gloffuse params.py: checks the parameter document (GLOFFUSE_PARAMS) before
# anything is built, and says what is wrong with it.
#
# One part of the script the gloffuse binary concatenates: header, compat.py,
# params.py, nodes.py, roughness_groups.py, view_groups.py, groups.py,
# runtime.py, then a main. Functions and constants only; uses
# max_name_bytes() from compat.py.
#
#   load_params(text) -> dict             parse and validate the parameter JSON
#   validate_params(params) -> params     raise ValueError saying what is wrong
# ---------------------------------------------------------------------------
import json
import math

DISTRIBUTIONS = ("BECKMANN", "GGX", "ASHIKHMIN_SHIRLEY")
CURVE_VARIABLES = ("roughness", "alpha")


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


def validate_params(params):
    """Check the parameter document; raise ValueError saying what is wrong."""
    if not isinstance(params, dict):
        raise ValueError("the parameter document must be a JSON object")
    groups = params.get("groups")
    if not isinstance(groups, list) or not groups:
        raise ValueError("the parameter document needs a non-empty 'groups' list")
    limit = max_name_bytes()
    seen = set()
    for index, spec in enumerate(groups):
        where = "groups[%d]" % index
        if not isinstance(spec, dict):
            raise ValueError("%s must be an object" % where)
        if spec.get("distribution") not in DISTRIBUTIONS:
            raise ValueError("%s.distribution is %r; expected one of %s"
                             % (where, spec.get("distribution"), ", ".join(DISTRIBUTIONS)))
        for key in ("correction_group", "shader_group"):
            name = spec.get(key)
            if not isinstance(name, str) or not name.strip():
                raise ValueError("%s.%s must be a non-empty string" % (where, key))
            if len(name.encode("utf-8")) > limit:
                raise ValueError("%s.%s %r is longer than Blender's %d-byte name limit"
                                 % (where, key, name, limit))
            if name in seen:
                raise ValueError("%s.%s %r is used twice" % (where, key, name))
            seen.add(name)
        view = spec.get("view")
        if view is not None:
            if not isinstance(view, dict):
                raise ValueError("%s.view must be an object" % where)
            for key in ("correction_group", "shader_group", "multiscatter_group", "image"):
                name = view.get(key)
                if not isinstance(name, str) or not name.strip():
                    raise ValueError("%s.view.%s must be a non-empty string" % (where, key))
                if len(name.encode("utf-8")) > limit:
                    raise ValueError("%s.view.%s %r is longer than Blender's %d-byte name limit"
                                     % (where, key, name, limit))
                if key != "image":
                    if name in seen:
                        raise ValueError("%s.view.%s %r is used twice" % (where, key, name))
                    seen.add(name)
            table = view.get("table")
            if not isinstance(table, dict) or not all(
                    isinstance(table.get(k), int) and table.get(k) >= 2 for k in ("width", "height")):
                raise ValueError("%s.view.table needs integer width and height of at least 2" % where)
        if not isinstance(spec.get("description", ""), str):
            raise ValueError("%s.description must be a string" % where)
        curve = spec.get("curve")
        if not isinstance(curve, dict):
            raise ValueError("%s.curve must be an object" % where)
        if curve.get("variable") not in CURVE_VARIABLES:
            raise ValueError("%s.curve.variable is %r; expected 'roughness' or 'alpha'"
                             % (where, curve.get("variable")))
        for key in ("numerator", "denominator"):
            coeffs = finite_list(curve.get(key), "%s.curve.%s" % (where, key))
            if not any(coeffs):
                raise ValueError("%s.curve.%s is identically zero" % (where, key))
    return params


def load_params(text):
    """Parse the JSON parameter document and validate it."""
    return validate_params(json.loads(text))
