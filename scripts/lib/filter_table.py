#!/usr/bin/env python3
"""Jitter and lag of fingertips, raw and smoothed by the client library's One Euro filter.

Reads handtrack-eval's --tips-csv (estimated and true fingertips per frame), runs every sequence's
poses through handtrack.PoseFilter (the C library's handtrack_filter, through the Python module)
and prints a Markdown table per motion (docs/FILTER.md):

- jitter: the frame-to-frame change of the fingertip error vector, |e_t - e_(t-1)| with
  e = estimate - truth, averaged over the 5 tips, over consecutive tracked frames; p50 and p95.
- lag: the delay s (frames, 0.1 steps) that best aligns the estimates with the truth, i.e. that
  minimises the mean |estimate_t - truth(t - s)| (truth interpolated linearly).
- mean: the mean fingertip error (mm) as handtrack-eval scores it.
- late truth: the p95 jitter of a perfect estimate one frame late (the truth of the frame
  before): what the motion alone contributes at one frame of lag. The rest is the tracker's own
  error changing from frame to frame, which a filter with at most a frame of lag cannot remove.

    filter_table.py TIPS_CSV [--min-cutoff HZ] [--beta B] [--d-cutoff HZ] [--sweep]
"""
import argparse
import csv
import math
import statistics
import sys

import handtrack

TIPS = 5


def read_sequences(path):
    sequences = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            truth = []
            for t in range(TIPS):
                cells = [row[f"true{t}_{a}"] for a in "xyz"]
                truth.append(None if "" in cells else [float(c) for c in cells])
            sequences.setdefault(row["sequence"], []).append({
                "time_s": float(row["time_s"]),
                "state": int(row["state"]),
                "est": [[float(row[f"est{t}_{a}"]) for a in "xyz"] for t in range(TIPS)],
                "truth": truth,
            })
    return sequences


def smoothed(frames, params):
    """The estimates after the library's filter (a fresh filter per sequence)."""
    pose_filter = handtrack.PoseFilter(**params)
    out = []
    for fr in frames:
        frame = handtrack.Frame()  # one hand, always the same id: the sequence is one hand's
        frame.epoch = 1
        frame.capture_ns = int(round(fr["time_s"] * 1e9)) + 1_000_000_000
        frame.hand_count = 1
        hand = frame.hand_records[0]
        hand.hand_id = 1
        hand.state = fr["state"]
        for t in range(TIPS):
            for k in range(3):
                hand.fingertips_mm[t][k] = fr["est"][t][k]
        pose_filter.apply(frame)
        out.append([[hand.fingertips_mm[t][k] for k in range(3)] for t in range(TIPS)])
    return out


def usable(fr):
    return fr["state"] == 1 and all(tip is not None for tip in fr["truth"])


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def jitter(frames, estimates):
    changes = []
    for i in range(1, len(frames)):
        if not (usable(frames[i]) and usable(frames[i - 1])):
            continue
        total = 0.0
        for t in range(TIPS):
            e_now = [estimates[i][t][k] - frames[i]["truth"][t][k] for k in range(3)]
            e_before = [estimates[i - 1][t][k] - frames[i - 1]["truth"][t][k] for k in range(3)]
            total += dist(e_now, e_before)
        changes.append(total / TIPS)
    return changes


def mean_error(frames, estimates, shift=0.0):
    """Mean |estimate_t - truth(t - shift)| over usable frames (truth interpolated)."""
    whole = int(math.floor(shift))
    frac = shift - whole
    total, n = 0.0, 0
    for i in range(whole + 1, len(frames)):
        a, b = frames[i - whole], frames[i - whole - 1]
        if not (usable(frames[i]) and usable(a) and usable(b)):
            continue
        for t in range(TIPS):
            truth = [(1 - frac) * a["truth"][t][k] + frac * b["truth"][t][k] for k in range(3)]
            total += dist(estimates[i][t], truth)
            n += 1
    return total / n if n else float("nan")


def lag(frames, estimates):
    shifts = [s / 10 for s in range(0, 51)]
    return min(shifts, key=lambda s: mean_error(frames, estimates, s))


def percentile(values, p):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(p / 100 * (len(ordered) - 1))))]


def measure(sequences, params):
    """Per motion (its seeds together): jitter p50 and p95 over all their frames, lag and mean
    error averaged over the seeds; raw and smoothed."""
    motions = {}
    for name, frames in sequences.items():
        raw = [fr["est"] for fr in frames]
        smooth = smoothed(frames, params)
        m = motions.setdefault(name.rsplit("-seed", 1)[0], {"raw": ([], [], []), "smooth": ([], [], []), "late": []})
        late = [frames[max(i - 1, 0)]["truth"] if usable(frames[max(i - 1, 0)]) else frames[i]["est"]
                for i in range(len(frames))]
        m["late"].extend(jitter(frames, late))
        for key, estimates in (("raw", raw), ("smooth", smooth)):
            m[key][0].extend(jitter(frames, estimates))
            m[key][1].append(lag(frames, estimates))
            m[key][2].append(mean_error(frames, estimates))
    rows = []
    for motion, m in motions.items():
        row = {"motion": motion, "late": percentile(m["late"], 95)}
        for key in ("raw", "smooth"):
            jit, lags, errors = m[key]
            row[key] = (statistics.median(jit), percentile(jit, 95), statistics.mean(lags), statistics.mean(errors))
        rows.append(row)
    return rows


def table(rows, params):
    lines = [f"One Euro filter: min_cutoff_hz {params['min_cutoff_hz']}, beta {params['beta']}, "
             f"d_cutoff_hz {params['d_cutoff_hz']}", "",
             "| motion | jitter p50 raw / smoothed (mm) | jitter p95 raw / smoothed (mm) | p95 ratio "
             "| lag raw / smoothed (frames) | mean error raw / smoothed (mm) | p95 of the truth 1 frame late (mm) |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows + [overall(rows)]:
        (p50r, p95r, lagr, mr), (p50s, p95s, lags, ms) = r["raw"], r["smooth"]
        lines.append(f"| {r['motion']} | {p50r:.2f} / {p50s:.2f} | {p95r:.2f} / {p95s:.2f} | {p95s / p95r:.2f} "
                     f"| {lagr:.1f} / {lags:.1f} | {mr:.2f} / {ms:.2f} | {r['late']:.2f} |")
    return "\n".join(lines)


def overall(rows):
    mean = lambda key, i: statistics.mean(r[key][i] for r in rows)  # noqa: E731
    return {"motion": "**mean**", "raw": tuple(mean("raw", i) for i in range(4)),
            "smooth": tuple(mean("smooth", i) for i in range(4)), "late": statistics.mean(r["late"] for r in rows)}


def meets_goal(rows):
    """The goal of docs/FILTER.md: p95 jitter at least halved, at most one frame more lag."""
    return all(r["smooth"][1] <= 0.5 * r["raw"][1] and r["smooth"][2] - r["raw"][2] <= 1.0 for r in rows)


def main():
    defaults = handtrack.PoseFilter().params
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tips_csv")
    parser.add_argument("--min-cutoff", type=float, default=defaults.min_cutoff_hz)
    parser.add_argument("--beta", type=float, default=defaults.beta)
    parser.add_argument("--d-cutoff", type=float, default=defaults.d_cutoff_hz)
    parser.add_argument("--sweep", action="store_true", help="try a grid of parameters (for choosing defaults)")
    args = parser.parse_args()
    sequences = read_sequences(args.tips_csv)
    if args.sweep:
        # For choosing the defaults: the least p95 jitter (mean ratio over the motions) among the
        # parameters that add at most one frame of lag in every motion.
        for min_cutoff in (0.5, 1.0, 2.0, 3.0):
            for beta in (0.01, 0.03, 0.05, 0.08, 0.12):
                params = {"min_cutoff_hz": min_cutoff, "beta": beta, "d_cutoff_hz": args.d_cutoff}
                rows = measure(sequences, params)
                mean_p95 = statistics.mean(r["smooth"][1] / r["raw"][1] for r in rows)
                mean_p50 = statistics.mean(r["smooth"][0] / r["raw"][0] for r in rows)
                worst_lag = max(r["smooth"][2] - r["raw"][2] for r in rows)
                print(f"min_cutoff {min_cutoff:4} beta {beta:5}: jitter ratio p50 {mean_p50:.2f} p95 {mean_p95:.2f} "
                      f"(mean over motions), extra lag worst {worst_lag:.1f} frames, "
                      f"mean error {overall(rows)['smooth'][3]:.2f} mm", flush=True)
        return 0
    params = {"min_cutoff_hz": args.min_cutoff, "beta": args.beta, "d_cutoff_hz": args.d_cutoff}
    rows = measure(sequences, params)
    print(table(rows, params))
    print()
    print("goal (p95 jitter at least halved, at most one frame more lag): "
          + ("met in every motion" if meets_goal(rows) else "NOT met"))
    return 0 if meets_goal(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
