#!/usr/bin/env python3
"""The package's document validators under plain CPython (no bpy).

    check_contract.py PACKAGE_DIR DOCUMENTS_DIR

DOCUMENTS_DIR holds the documents Rust really builds, one KIND.json each (KIND a kind of
contract.py: generate_document, furnace_document, audit_document, bench_library_document;
a suffix after "+" tells apart two of one kind). Each must pass contract.py's check_fields,
and the generate document params.py's load_params too; then each kind of bad document,
made from a good one, must be refused with its message. Prints "N passed, M failed" and
exits 1 on any failure.

contract.py imports nothing. params.py imports three functions from compat.py, which
imports bpy; this script gives it a compat module of its own instead (Blender 5.0, and
Blender's 63-byte names), registered before the package is imported, so the package
itself is loaded unchanged and holds no stand-in.
"""
import copy
import json
import os
import sys
import types


def load_package(package_dir):
    package = types.ModuleType("gloffuse_blender")
    package.__path__ = [package_dir]
    sys.modules["gloffuse_blender"] = package
    compat = types.ModuleType("gloffuse_blender.compat")
    compat.max_name_bytes = lambda: 63
    compat.masking_family = lambda first: "height-correlated" if (5, 0) >= tuple(first) else "separable"
    compat.blender_at_least = lambda version: (5, 0) >= tuple(version)
    sys.modules["gloffuse_blender.compat"] = compat
    from gloffuse_blender import contract, params
    return contract, params


def without(document, *path):
    document = copy.deepcopy(document)
    inner = document
    for key in path[:-1]:
        inner = inner[key]
    del inner[path[-1]]
    return document


def with_(document, value, *path):
    document = copy.deepcopy(document)
    inner = document
    for key in path[:-1]:
        inner = inner[key]
    inner[path[-1]] = value
    return document


def bad_cases(docs):
    """(what, kind, document, the message it must be refused with)."""
    generate = docs["generate_document"]
    furnace = docs["furnace_document"]
    audit = docs["audit_document+groups"]
    scan = docs["audit_document"]
    bench = docs["bench_library_document"]
    return [
        ("an unknown field", "generate_document", with_(generate, "exact", "colour_model"),
         "the document: unknown field 'colour_model' (a generate_document holds "),
        ("a missing field", "generate_document", without(generate, "previews"),
         "the document: missing field 'previews' (every generate_document has it)"),
        ("an unknown field in a family", "generate_document",
         with_(generate, 1, "groups", 0, "families", 1, "extra"),
         "the document.groups[0].families[1]: unknown field 'extra'"),
        ("a catalog without its uuid", "generate_document", without(generate, "catalogs", "helper", "uuid"),
         "the document.catalogs.helper: missing field 'uuid' (every catalog has it)"),
        ("groups not a list", "generate_document", with_(generate, {}, "groups"),
         "the document.groups must be a list"),
        ("no furnace section", "furnace_document", without(furnace, "furnace"),
         "the document: missing field 'furnace'"),
        ("a furnace without the generate fields", "furnace_document", without(furnace, "catalogs"),
         "the document: missing field 'catalogs' (every furnace_document has it)"),
        ("a furnace section with an unknown field", "furnace_document", with_(furnace, 2, "furnace", "bounces"),
         "the document.furnace: unknown field 'bounces'"),
        ("part of the generate fields", "audit_document", with_(scan, [], "groups"),
         "the document: missing field 'gloffuse_version'"),
        ("an audit section with an unknown field", "audit_document", with_(scan, 1, "audit", "bounces"),
         "the document.audit: unknown field 'bounces'"),
        ("a rule range with an unknown field", "audit_document",
         with_(audit, "x", "audit", "rules", 0, "effect"),
         "the document.audit.rules[0]: unknown field 'effect'"),
        ("a fix without its scale", "audit_document", without(audit, "audit", "fix", 0, "scale"),
         "the document.audit.fix[0]: missing field 'scale'"),
        ("a bench library without its count", "bench_library_document", without(bench, "bench_library", "count"),
         "the document.bench_library: missing field 'count'"),
        ("not an object", "bench_library_document", [bench], "the document must be a JSON object"),
        ("a result line with an unknown field", "furnace_result",
         {"blender_version": "5.0.0", "output": "f.exr", "width": 4, "height": 4, "render_seconds": 1.0, "seconds": 1},
         "the document: unknown field 'seconds'"),
        ("an audit result's finding without its twin", "audit_result",
         {"blender_version": "5.0.0", "file": "a.blend", "scan_seconds": 0.1,
          "materials": [{"name": "m", "library": None, "users": 1, "cell": None, "twin_cell": None,
                         "replaced": 0, "error": None, "waivers": [],
                         "findings": [{"rule": "r", "node": ["m"], "node_type": "Material", "detail": {}}]}]},
         "the document.materials[0].findings[0]: missing field 'twin'"),
        ("an audit result's waiver without its type", "audit_result",
         {"blender_version": "5.0.0", "file": "a.blend", "scan_seconds": 0.1,
          "materials": [{"name": "m", "library": None, "users": 1, "cell": None, "twin_cell": None,
                         "replaced": 0, "error": None, "findings": [],
                         "waivers": [{"node": ["m"], "node_type": "Material", "value": "*: x"}]}]},
         "the document.materials[0].waivers[0]: missing field 'type'"),
    ]


def value_cases(generate):
    """(what, document, the message load_params refuses it with): params.py's own checks,
    after the fields."""
    return [
        ("an unknown colour model", with_(generate, "nope", "color_model"), "color_model is 'nope'"),
        ("a zero curve", with_(with_(generate, [0.0], "groups", 0, "families", 0, "curve", "numerator"),
                               [0.0], "groups", 0, "families", 1, "curve", "numerator"),
         "curve.numerator is identically zero"),
        ("a bad masking", with_(generate, "both", "groups", 0, "families", 0, "masking"),
         "groups[0].families: masking 'both' is not one of"),
        ("a name used twice", with_(generate, generate["groups"][0]["shader_group"], "groups", 1, "shader_group"),
         "is used twice"),
    ]


def main(argv):
    contract, params = load_package(argv[1])
    docs = {}
    for name in sorted(os.listdir(argv[2])):
        with open(os.path.join(argv[2], name), encoding="utf-8") as handle:
            docs[name[:-len(".json")]] = json.load(handle)
    passed = failed = 0

    def expect(what, run, message=None):
        nonlocal passed, failed
        try:
            run()
            error = None
        except ValueError as caught:
            error = str(caught)
        if message is None and error is None or message is not None and error is not None and message in error:
            passed += 1
        else:
            failed += 1
            print("FAIL %s: wanted %s, got %s" % (what, "acceptance" if message is None else repr(message),
                                                  "acceptance" if error is None else repr(error)))

    for name, document in docs.items():
        expect("the real %s" % name, lambda d=document, k=name.split("+")[0]: contract.check_fields(d, k))
    generate = docs["generate_document"]
    expect("load_params on the real generate document", lambda: params.load_params(json.dumps(generate)))
    for what, kind, document, message in bad_cases(docs):
        expect(what, lambda d=document, k=kind: contract.check_fields(d, k), message)
    for what, document, message in value_cases(generate):
        expect(what, lambda d=document: params.load_params(json.dumps(d)), message)
    expect("load_params on a generate document with an unknown field",
           lambda: params.load_params(json.dumps(with_(generate, 1, "furnace"))), "unknown field 'furnace'")
    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
