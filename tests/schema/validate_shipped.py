#!/usr/bin/python3
"""Every shipped scene and spec validates against the JSON Schema `flume schema KIND` prints (Debian
python3-jsonschema; skipped, exit 77, without it). The schemas themselves are checked as draft 2020-12.

    validate_shipped.py FLUME SOURCE_DIR
"""
import glob
import json
import os
import re
import subprocess
import sys

try:
    import jsonschema
except ImportError:
    print("skipped: /usr/bin/python3 lacks jsonschema (Debian: apt-get install python3-jsonschema)")
    sys.exit(77)

flume, src = sys.argv[1], sys.argv[2]
# The shipped documents of each kind the command describes.
shipped = {
    "scene": ["scenes/dam_break/*.json", "scenes/debris/*.json", "scenes/validation/*.json", "scenes/waseda/*.json",
              "bench/scenes/*.json", "tests/examples/*.json", "tests/schema/*.json"],
    "campaign": ["scenes/campaigns/*.json"],
    "calibration": ["docs/calibration.md"],  # no spec file ships: the spec example of the docs (```json blocks)
    "study": ["scenes/studies/*.json"],
}


def documents(path):
    """A .json file's object, or the JSON objects of a Markdown file's ```json blocks."""
    if not path.endswith(".md"):
        return [json.load(open(path))]
    blocks = re.findall(r"^```json\n(.*?)^```", open(path).read(), re.S | re.M)
    return [json.loads(b) for b in blocks]


kinds = [k for k in shipped if subprocess.run([flume, "schema", k], capture_output=True).returncode == 0]
failures, count = [], 0
for kind in kinds:
    schema = json.loads(subprocess.run([flume, "schema", kind], capture_output=True, check=True).stdout)
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    files = sorted(f for pattern in shipped[kind] for f in glob.glob(os.path.join(src, pattern)))
    if not files:
        print(f"note: no shipped {kind} documents (patterns: {shipped[kind]})")
    for f in files:
        for doc in documents(f):
            count += 1
            for e in validator.iter_errors(doc):
                failures.append(f"{os.path.relpath(f, src)}: {'.'.join(map(str, e.absolute_path))}: {e.message}")
print(f"{count} shipped documents of kinds {', '.join(kinds)} checked against their schemas")
if failures:
    print("\n".join(failures))
    sys.exit(1)
