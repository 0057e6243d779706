#!/usr/bin/env python3
"""Validates a JSON document against a JSON Schema (draft-07), using Debian's python3-jsonschema.

usage: validate_json_schema.py SCHEMA DOCUMENT   (exit 0 if valid; prints every error otherwise)
"""
import json
import sys

import jsonschema


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1], encoding="utf-8") as f:
        schema = json.load(f)
    with open(sys.argv[2], encoding="utf-8") as f:
        document = json.load(f)
    validator = jsonschema.Draft7Validator(schema, format_checker=jsonschema.FormatChecker())
    errors = sorted(validator.iter_errors(document), key=lambda e: list(e.path))
    for e in errors[:20]:
        print(f"{sys.argv[2]}: {'/'.join(map(str, e.path)) or '(root)'}: {e.message}", file=sys.stderr)
    if errors:
        print(f"{sys.argv[2]}: {len(errors)} schema error(s)", file=sys.stderr)
        return 1
    print(f"{sys.argv[2]}: valid against {schema.get('$id', sys.argv[1])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
