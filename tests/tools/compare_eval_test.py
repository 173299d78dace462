#!/usr/bin/env python3
"""scripts/compare-eval on two hand-made handtrack-eval JSON files: what moved is shown before ->
after, what did not once; the sequences that moved are listed and counted; files of different
sequences, or not handtrack-eval's, give one line and exit 1.
    compare_eval_test.py SCRIPT WORKDIR"""
import json
import os
import subprocess
import sys

script, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)


def score(mean, right, below30=90.0, joints=None):
    s = {"mean_fingertip_error_mm": mean, "pct_frames_below_mm": {"30": below30}, "pct_frames_without_pose": 0.0,
         "handedness": {"frames_with_pose": 300, "pct_frames_correct": right}}
    if joints is not None:
        s["joints"] = {"frames_scored": 300, "mean_error_mm": joints}
    return s


def write(name, sequences, overall):
    path = os.path.join(work, name)
    with open(path, "w") as f:
        json.dump({"overall": overall, "groups": {"view": {"back": overall}},
                   "sequences": [dict(score(*s), name=n) for n, s in sequences.items()]}, f)
    return path


def run(*args):
    p = subprocess.run([sys.executable, script, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


failures = []


def check(condition, what):
    if not condition:
        failures.append(what)


before = write("before.json", {"steady": (10.0, 100.0), "better": (30.0, 60.0), "worse": (8.0, 100.0)},
               score(16.0, 86.67, joints=12.0))
after = write("after.json", {"steady": (10.5, 100.0), "better": (20.0, 99.0), "worse": (12.0, 100.0)},
              score(14.17, 99.67, joints=11.5))
code, out, err = run(before, after)
check(code == 0, f"exit {code}: {err}")
check("| all (3 sequences) | 16.00 -> 14.17 | 90.00 | 0.00 | 86.67 -> 99.67 | 12.00 -> 11.50 |" in out,
      "overall row:\n" + out)
check("| view back | 16.00 -> 14.17 |" in out, "group row:\n" + out)
check("2 of 3 sequences moved by more than 2 mm or 1 point of handedness: 1 gained, 1 lost." in out, out)
check("| better | 30.00 -> 20.00 | 90.00 | 0.00 | 60.00 -> 99.00 | - |" in out,
      "moved row, no joints scored:\n" + out)
check("| worse | 8.00 -> 12.00 |" in out, "moved row:\n" + out)
check("| steady |" not in out, "a sequence within the limits is not listed:\n" + out)

other = write("other.json", {"steady": (10.0, 100.0)}, score(10.0, 100.0))
code, out, err = run(before, other)
check(code == 1 and err.count("\n") == 1 and "score different sequences" in err, f"exit {code}: {err}")

broken = os.path.join(work, "broken.json")
with open(broken, "w") as f:
    f.write("{not json")
code, out, err = run(broken, after)
check(code == 1 and err.count("\n") == 1 and "broken.json: not handtrack-eval's JSON" in err, f"exit {code}: {err}")

for f in failures:
    print("FAILED:", f)
sys.exit(1 if failures else 0)
