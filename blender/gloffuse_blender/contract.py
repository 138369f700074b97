# ---------------------------------------------------------------------------
# gloffuse contract.py: the fields of every document gloffuse sends a job and of
# every result line a job prints, defined once.
#
# A module of the gloffuse_blender package. Plain Python: it imports nothing, so
# it runs without Blender (tests/contract_fields.rs runs it under CPython).
#
#   CONTRACT                       each kind of object: its required and optional
#                                  fields, and which of them hold objects
#   check_fields(value, kind, where) -> value
#                                  raise ValueError naming an unknown or a
#                                  missing field, in `value` or an object in it
#
# A field maps to "" (a value: its type and range are the job's to check), to a
# kind (an object of that kind) or to "KIND[]" (a list of them). "flatten" names
# kinds whose fields the object holds as its own: "required" ones always,
# "optional" ones all or none. The Rust side's documents and result types are
# checked against CONTRACT by the library's tests (crates/gloffuse/src/contract.rs),
# which read it as JSON: keep it JSON (double quotes, no trailing commas).
# ---------------------------------------------------------------------------

CONTRACT = {
    "generate_document": {
        "required": {
            "gloffuse_version": "", "height_correlated_from": "", "color_model": "",
            "catalogs": "catalogs", "asset_author": "", "asset_license": "", "asset_copyright": "",
            "previews": "", "groups": "group[]"
        }
    },
    "catalogs": {"required": {"shader": "catalog", "helper": "catalog"}},
    "catalog": {"required": {"uuid": "", "path": "", "simple_name": ""}},
    "group": {
        "required": {
            "distribution": "", "engine": "", "correction_group": "", "shader_group": "",
            "families": "family[]"
        },
        "optional": {
            "normal_group": "", "view": "view", "layered_group": "", "anisotropic_group": "",
            "glass_group": "", "refraction_group": ""
        }
    },
    "view": {"optional": {"correction_group": "", "shader_group": "", "multiscatter_group": ""}},
    "family": {
        "required": {"masking": "", "coefficients_source": "", "description": "", "curve": "curve"},
        "optional": {
            "image": "", "table": "albedo_table",
            "coat_image": "", "coat_table": "coat_table", "coat_gain_image": "",
            "anisotropic_image": "", "anisotropic_table": "anisotropic_table",
            "glass_image": "", "glass_table": "glass_table"
        }
    },
    "curve": {"required": {"variable": "", "numerator": "", "denominator": ""}},
    "albedo_table": {"required": {"width": "", "height": "", "values": "", "average": ""}},
    "coat_table": {
        "required": {"size": "", "slices": "", "ior": "", "ior_max": "", "z_max": "", "values": ""},
        "optional": {"gain": ""}
    },
    "anisotropic_table": {"required": {"size": "", "azimuths": "", "values": ""}},
    "glass_table": {
        "required": {
            "size": "", "slices": "", "ior": "", "ior_max": "", "z_max": "", "from_version": "",
            "form": "", "glass_group": "", "refraction_entering": "", "refraction_leaving": ""
        },
        "optional": {
            "glass_entering": "", "glass_leaving": "", "reflection": "",
            "glass_average_entering": "", "glass_average_leaving": "",
            "refraction_average_entering": "", "refraction_average_leaving": ""
        }
    },
    "furnace_document": {"required": {"furnace": "furnace"}, "flatten": {"generate_document": "required"}},
    "furnace": {
        "required": {
            "engine": "", "solid": "", "cell": "", "columns": "", "samples": "", "seed": "",
            "radius_fraction": "", "color": "", "output": "", "threads": "", "spheres": ""
        }
    },
    "audit_document": {"required": {"audit": "audit"}, "flatten": {"generate_document": "optional"}},
    "audit": {
        "required": {
            "output": "", "twin_output": "", "render": "", "cell": "", "samples": "", "seed": "",
            "threads": "", "radius_fraction": "", "rules": "rule_range[]", "twin_names": "twin_names",
            "fix": "fix_item[]"
        }
    },
    "rule_range": {"required": {"id": "", "from": "", "before": ""}},
    "twin_names": {"required": {"multiscatter": "", "layered": "", "anisotropic": "", "glass": "",
                                "refraction": ""}},
    "fix_item": {"required": {"material": "", "scale": ""}},
    "bench_library_document": {"required": {"bench_library": "bench_library"}},
    "bench_library": {"required": {"output": "", "count": "", "first": ""}},
    "generate_result": {
        "required": {"blender_version": "", "saved": ""},
        "optional": {"groups": "", "renamed": "", "refused": ""}
    },
    "furnace_result": {
        "required": {"blender_version": "", "output": "", "width": "", "height": "", "render_seconds": ""}
    },
    "audit_result": {
        "required": {"blender_version": "", "file": "", "materials": "audit_material[]", "scan_seconds": ""},
        "optional": {
            "needs": "", "output": "", "twin_output": "", "width": "", "height": "", "columns": "",
            "render_seconds": "", "file_findings": "audit_finding[]", "fixed": "audit_fixed"
        }
    },
    "audit_material": {
        "required": {
            "name": "", "library": "", "users": "", "cell": "", "twin_cell": "", "replaced": "",
            "findings": "audit_finding[]", "error": "", "waivers": "audit_waiver[]"
        }
    },
    "audit_waiver": {"required": {"node": "", "node_type": "", "value": "", "type": ""}},
    "audit_finding": {
        "required": {"rule": "", "node": "", "node_type": "", "detail": "", "twin": ""},
        "optional": {"metal_twin": ""}
    },
    "audit_fixed": {"required": {"path": "", "replaced": "", "materials": ""}},
    "bench_library_result": {"required": {"output": "", "materials": ""}}
}


def check_fields(value, kind, where="the document"):
    """`value` if it holds exactly the fields CONTRACT gives `kind`, and every
    object in it those of its own kind; ValueError naming the field otherwise."""
    if not isinstance(value, dict):
        raise ValueError("%s must be a JSON object" % where)
    spec = CONTRACT[kind]
    required = dict(spec.get("required", {}))
    optional = dict(spec.get("optional", {}))
    for flat, presence in spec.get("flatten", {}).items():
        inner = CONTRACT[flat]
        if presence == "required" or any(key in value for key in inner.get("required", {})):
            required.update(inner.get("required", {}))
            optional.update(inner.get("optional", {}))
    for key in value:
        if key not in required and key not in optional:
            raise ValueError("%s: unknown field %r (a %s holds %s)"
                             % (where, key, kind, ", ".join(sorted(set(required) | set(optional)))))
    for key in required:
        if key not in value:
            raise ValueError("%s: missing field %r (every %s has it)" % (where, key, kind))
    for key, inner in list(required.items()) + list(optional.items()):
        item = value.get(key)
        if not inner or item is None:
            continue
        if inner.endswith("[]"):
            if not isinstance(item, list):
                raise ValueError("%s.%s must be a list" % (where, key))
            for index, element in enumerate(item):
                check_fields(element, inner[:-2], "%s.%s[%d]" % (where, key, index))
        else:
            check_fields(item, inner, "%s.%s" % (where, key))
    return value
