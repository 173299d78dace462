#!/usr/bin/env python3
"""Runs handtrack-bench briefly and checks its JSON against SPEC.md "Benchmark output"."""
import csv
import json
import math
import subprocess
import sys

exe, out = sys.argv[1], sys.argv[2]
subprocess.run([exe, "--frames", "20", "--json", out], check=True, stdout=subprocess.DEVNULL)
with open(out) as f:
    table = json.load(f)
failures = []
TWO_HANDS = ("two_hands_late_fusion_2p_10it", "two_hands_late_fusion_2p_10it_one_thread")
SPREAD_CHECKS = ("depth_only_2p_10it_spread_checks", "late_fusion_2p_10it_spread_checks")
for name in ("depth_only_1p_10it", "depth_only_2p_10it", "late_fusion_2p_10it", "late_fusion_2p_10it_max_hands_2") + TWO_HANDS + SPREAD_CHECKS:
    entry = table.get(name)
    if entry is None:
        failures.append(f"{name}: missing")
        continue
    for key in ("fps", "preprocess_ms", "optimize_ms"):
        value = entry.get(key)
        if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            failures.append(f"{name}.{key} = {value!r}")
    latency = entry.get("latency_ms", {})
    if not (0 < latency.get("p50", 0) <= latency.get("p99", 0)):
        failures.append(f"{name}.latency_ms = {latency!r}")
    if (entry.get("width"), entry.get("height")) != (320, 240):
        failures.append(f"{name}: resolution {entry.get('width')}x{entry.get('height')}")
if not failures and (table["depth_only_2p_10it"]["particles"], table["late_fusion_2p_10it"]["particles"]) != (2, 2):
    failures.append("the 2-particle configurations do not run 2 particles")
# The two-hand configurations track two hands (the scene shows two from its first frame) and say
# how much of their work overlapped: between 1 (one after the other) and 2 (side by side).
for name in TWO_HANDS:
    entry = table.get(name, {})
    if not 1.5 <= entry.get("hands_per_frame", 0) <= 2:
        failures.append(f"{name}: {entry.get('hands_per_frame')!r} hands per frame")
    if not 0.5 <= entry.get("hand_overlap", 0) <= 2.05:
        failures.append(f"{name}: hand_overlap {entry.get('hand_overlap')!r}")
# --only measures the configurations named and no other; an unknown name is one error line.
subprocess.run([exe, "--frames", "10", "--only", "late_fusion_2p_10it", "--json", out], check=True,
               stdout=subprocess.DEVNULL)
with open(out) as f:
    only = json.load(f)
if sorted(only) != ["late_fusion_2p_10it"]:
    failures.append(f"--only late_fusion_2p_10it measured {sorted(only)}")
# The scenes' subject: 7 unless --seed says another.
if table["late_fusion_2p_10it"].get("seed") != 7:
    failures.append(f"default seed {table['late_fusion_2p_10it'].get('seed')!r}, not 7")
subprocess.run([exe, "--frames", "10", "--seed", "3", "--only", "late_fusion_2p_10it", "--json", out], check=True,
               stdout=subprocess.DEVNULL)
with open(out) as f:
    seeded = json.load(f)
if seeded["late_fusion_2p_10it"].get("seed") != 3:
    failures.append(f"--seed 3 measured seed {seeded['late_fusion_2p_10it'].get('seed')!r}")
# --runs N: every configuration measured N times; each figure is the median of the runs, each
# run's fps listed (one run by default).
if table["late_fusion_2p_10it"].get("fps_runs") != [table["late_fusion_2p_10it"]["fps"]]:
    failures.append(f"one run: fps_runs {table['late_fusion_2p_10it'].get('fps_runs')!r}")
subprocess.run([exe, "--frames", "10", "--runs", "3", "--only", "late_fusion_2p_10it", "--only", "depth_only_1p_10it",
                "--json", out], check=True, stdout=subprocess.DEVNULL)
with open(out) as f:
    repeated = json.load(f)
for name, entry in sorted(repeated.items()):
    fps_runs = entry.get("fps_runs", [])
    if entry.get("runs") != 3 or len(fps_runs) != 3 or not all(math.isfinite(v) and v > 0 for v in fps_runs):
        failures.append(f"--runs 3, {name}: runs {entry.get('runs')!r}, fps_runs {fps_runs!r}")
    elif entry["fps"] != sorted(fps_runs)[1]:
        failures.append(f"--runs 3, {name}: fps {entry['fps']!r} is not the median of {fps_runs!r}")
# --frames-csv: a row per frame of every run of every configuration measured; a late-fusion run's
# first frame is its (re)start search (hundreds of iterations), a tracked frame 2 particles x 10.
frames_csv = out + ".frames.csv"
subprocess.run([exe, "--frames", "12", "--runs", "2", "--only", "late_fusion_2p_10it", "--only", "depth_only_1p_10it",
                "--frames-csv", frames_csv], check=True, stdout=subprocess.DEVNULL)
with open(frames_csv) as f:
    rows = list(csv.DictReader(f))
keys = sorted({(r["configuration"], r["run"]) for r in rows})
if keys != [(c, r) for c in ("depth_only_1p_10it", "late_fusion_2p_10it") for r in ("0", "1")] or len(rows) != 48:
    failures.append(f"--frames-csv: {len(rows)} rows of {keys!r}")
else:
    late = [r for r in rows if r["configuration"] == "late_fusion_2p_10it" and r["run"] == "0"]
    if [r["frame"] for r in late] != [str(i) for i in range(12)]:
        failures.append(f"--frames-csv: frames {[r['frame'] for r in late]!r}")
    if int(late[0]["iterations"]) < 100 or not all(int(r["iterations"]) >= 20 for r in late):
        failures.append(f"--frames-csv: iterations {[r['iterations'] for r in late]!r}")
    if not all(float(r["preprocess_ms"]) > 0 and float(r["optimize_ms"]) > 0 and r["hands"] == "1" for r in late):
        failures.append(f"--frames-csv: {late[1]!r}")
# An output that cannot be written is one error line before anything is measured (a full run here
# takes minutes; the timeout says it did not run).
for option in ("--json", "--frames-csv"):
    unwritable = subprocess.run([exe, option, "/nonexistent-dir/out"], capture_output=True, text=True, timeout=10)
    lines = unwritable.stderr.strip().splitlines()
    if unwritable.returncode == 0 or len(lines) != 1 or "/nonexistent-dir/out" not in lines[0]:
        failures.append(f"{option} /nonexistent-dir/out: exit {unwritable.returncode}, stderr {unwritable.stderr!r}")
bad_runs = subprocess.run([exe, "--runs", "0"], capture_output=True, text=True)
if bad_runs.returncode == 0 or len(bad_runs.stderr.strip().splitlines()) != 1 or "--runs" not in bad_runs.stderr:
    failures.append(f"--runs 0: exit {bad_runs.returncode}, stderr {bad_runs.stderr!r}")
bad = subprocess.run([exe, "--only", "no_such_configuration"], capture_output=True, text=True)
if bad.returncode == 0 or len(bad.stderr.strip().splitlines()) != 1 or "no_such_configuration" not in bad.stderr:
    failures.append(f"--only no_such_configuration: exit {bad.returncode}, stderr {bad.stderr!r}")
for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
