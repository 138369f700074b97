#!/usr/bin/env python3
"""Checks generated scripts without Blender (plain CPython).

    check_script.py REFERENCE.py CASE1.py EXPECT1.json [CASE2.py EXPECT2.json ...]

For every case: the script parses; GLOFFUSE_PARAMS is a plain string literal whose JSON
equals EXPECT (the parameter document the test meant to send); and the script's syntax
tree, with that literal blanked, is identical to REFERENCE's — so no text in the
parameters became code. Prints "N passed, M failed" and exits 1 on any failure.
"""
import ast
import json
import sys


def blanked_tree(source):
    tree = ast.parse(source)
    literal = None
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == "GLOFFUSE_PARAMS" for t in node.targets):
            if not (isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)):
                raise AssertionError("GLOFFUSE_PARAMS is not a plain string literal")
            if literal is not None:
                raise AssertionError("GLOFFUSE_PARAMS is assigned twice")
            literal = node.value.value
            node.value = ast.Constant("")
    if literal is None:
        raise AssertionError("no GLOFFUSE_PARAMS assignment")
    return ast.dump(tree), literal


def main(argv):
    with open(argv[1], encoding="utf-8") as handle:
        reference, _ = blanked_tree(handle.read())
    passed = failed = 0
    for script, expect in zip(argv[2::2], argv[3::2]):
        try:
            with open(script, encoding="utf-8") as handle:
                dump, literal = blanked_tree(handle.read())
            with open(expect, encoding="utf-8") as handle:
                wanted = json.load(handle)
            if json.loads(literal) != wanted:
                raise AssertionError("parameters did not round-trip")
            if dump != reference:
                raise AssertionError("the script's code differs from the reference")
            passed += 1
        except Exception as error:  # report every case, then fail
            failed += 1
            print("FAIL %s: %s" % (script, error))
    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
