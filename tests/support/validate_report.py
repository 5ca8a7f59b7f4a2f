"""Validates run reports against docs/report.schema.json (Debian's python3-jsonschema).

    /usr/bin/python3 tests/support/validate_report.py report.json [more.json ...]

Prints one line per invalid report (the file, the key's path, what is wrong) and exits 1 when
any is invalid; exits 0 when every report holds to the schema.
"""

import json
import pathlib
import sys

import jsonschema

SCHEMA = pathlib.Path(__file__).resolve().parents[2] / "docs" / "report.schema.json"


def main(paths):
    schema = json.loads(SCHEMA.read_text())
    validator = jsonschema.Draft202012Validator(schema)
    invalid = 0
    for path in paths:
        report = json.loads(pathlib.Path(path).read_text())
        for error in validator.iter_errors(report):
            where = "/".join(str(part) for part in error.absolute_path) or "(the report)"
            print(f"{path}: {where}: {error.message}")
            invalid += 1
    return 1 if invalid else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
