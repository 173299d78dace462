#!/usr/bin/env python3
"""README.md documents the service: its sections exist, and the configuration reference names
every field `handtrackd --print-config` prints (so a new field cannot go undocumented).

    check_readme.py SOURCE_DIR HANDTRACKD
"""
import re
import subprocess
import sys

src, handtrackd = sys.argv[1], sys.argv[2]
readme = open(f"{src}/README.md", encoding="utf-8").read()
failures = []

sections = ["Install as a service", "Read poses from C, C++ and Python", "Configuration reference",
            "Troubleshooting"]
for title in sections:
    if not re.search(rf"^##+ {re.escape(title)}\s*$", readme, re.M):
        failures.append(f"README.md has no section '{title}'")

match = re.search(r"^## Configuration reference\s*$(.*?)(?=^## )", readme, re.M | re.S)
reference = match.group(1) if match else ""
config = subprocess.run([handtrackd, "--print-config"], check=True, capture_output=True,
                        text=True).stdout
table, fields = None, []
for line in config.splitlines():
    if m := re.match(r"^\[([a-z_.]+)\]$", line):
        table = m.group(1)
    elif m := re.match(r"^([a-z_0-9]+) = ", line):
        fields.append(f"{table}.{m.group(1)}")
if len(fields) < 40:
    failures.append(f"only {len(fields)} fields parsed from --print-config")
for field in fields:
    table, key = field.rsplit(".", 1)
    # A row of the table for `table`, naming the key in backquotes.
    if not re.search(rf"`{re.escape(field)}`|^\|\s*`\[{re.escape(table)}\]`.*`{re.escape(key)}`",
                     reference, re.M):
        failures.append(f"configuration reference lacks {field} "
                        "(regenerate the table with tests/service/config_reference.py)")
for troubleshooting in ["no camera", "permission denied", "stale segment"]:
    if troubleshooting not in readme.lower():
        failures.append(f"Troubleshooting does not cover '{troubleshooting}'")
for f in failures:
    print("FAIL:", f)
print(f"{len(fields)} configuration fields checked" if not failures else f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
