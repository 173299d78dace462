#!/usr/bin/env python3
"""Prints the README's configuration reference table from `handtrackd --print-config` (the
comments there carry meaning, range and [live]). Regenerate after adding a field:

    tests/service/config_reference.py build/daemon/handtrackd
and paste over the table under "## Configuration reference" (check_readme.py checks coverage).
"""
import re
import subprocess
import sys

config = subprocess.run([sys.argv[1], "--print-config"], check=True, capture_output=True, text=True).stdout
table, comments = None, []
print("| field | default | range | meaning |")
print("|---|---|---|---|")
for line in config.splitlines():
    if m := re.match(r"^\[([a-z_.]+)\]$", line):
        table, comments = m.group(1), []
    elif line.startswith("# ") and table:
        comments.append(line[2:])
    elif (m := re.match(r"^([a-z_0-9]+) = (.*)$", line)) and table:
        desc, comments = " ".join(comments), []
        live = " **[live]**" if "[live]" in desc else ""
        desc = desc.replace(" [live]", "").replace("|", "\\|")
        limits = ""
        if r := re.search(r" \(allowed range ([^)]*)\)", desc):
            limits, desc = r.group(1), desc.replace(r.group(0), "")
        value = m.group(2).replace("'", '"')
        print(f"| `{table}.{m.group(1)}` | `{value}` | {limits} | {desc}{live} |")
