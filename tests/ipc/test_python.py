#!/usr/bin/env python3
"""The Python module reads real frames from a real writer process, every hand field by field.

Environment (set by ctest): HANDTRACK_CLIENT_LIB, IPC_TEST_WRITER, HANDTRACK_EXAMPLE
(clients/python/examples/print_poses.py), and either PYTHONPATH (clients/python: the source tree)
or HANDTRACK_EXPECT_INSTALLED (the venv that `pip install ./clients/python` installed into, by
python_package.sh).
"""
import asyncio
import ctypes
import os
import subprocess
import sys
import time

import handtrack

failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message, file=sys.stderr)


def checksum(frame):
    """FNV-1a 32 of the record with epoch, publish_ns and the checksum (the last hand's
    params[25]) zeroed (test_pattern.hpp)."""
    copy = handtrack.Frame.from_buffer_copy(bytes(frame))
    copy.epoch = 0
    copy.publish_ns = 0
    copy.hand_records[handtrack.MAX_HANDS - 1].params[25] = 0.0
    h = 2166136261
    for b in bytes(copy):
        h = ((h ^ b) * 16777619) & 0xFFFFFFFF
    return h


def expected_hand(frame, k):
    """make_test_hand() of tests/ipc/test_pattern.hpp, in Python."""
    f = float(frame % 1000)
    base = float(frame % 4096) + 500.0 * k
    return {
        "hand_id": k + 1, "handedness": "right" if k == 0 else "left",
        "handedness_confidence": (frame % 64) / 64.0,
        "state": 1 + (frame + k) % 2, "confidence": (frame % 100) / 128.0 + k / 1024.0,
        "energy": f * 0.5 + k, "optimize_ms": f * 0.25 + 2 + k,
        "params": [float(frame)] + [frame + i * 0.5 + k * 1000.0 for i in range(1, 25)],
        "joints_mm": [[base + j * 3 + a for a in range(3)] for j in range(21)],
        "fingertips_mm": [[base + 100 + t * 3 + a for a in range(3)] for t in range(5)],
        "palm_center_mm": [base + 200 + a for a in range(3)],
        "palm_normal": [0.0, 0.0, -1.0 if k == 0 else 1.0],
        "pinch_distance_mm": (frame % 256) * 0.5 + k, "pinch_strength": ((frame + k) % 4) * 0.25,
        "hand_scale": [1.0 + (frame % 8) * 0.125, 1.25 + 0.125 * k, 0.75],
    }


def check_frame(frame, epoch):
    """A frame of make_test_record() (test_pattern.hpp), field by field, through frame.hands."""
    where = f"frame {frame.frame}"
    f = float(frame.frame % 1000)
    check(frame.epoch == epoch, f"{where}: epoch {frame.epoch} != {epoch}")
    check(frame.publish_ns > 0, f"{where}: publish_ns not stamped")
    check(frame.capture_ns == frame.frame * 1000 + 7, f"{where}: capture_ns")
    check((frame.grab_ms, frame.preprocess_ms, frame.optimize_ms, frame.publish_ms)
          == (f * 0.25, f * 0.25 + 1, f * 0.25 + 2, f * 0.25 + 3), f"{where}: timings")
    check(frame.hand_records[handtrack.MAX_HANDS - 1].params[25] == float(checksum(frame)), f"{where}: checksum")
    hands = frame.hands
    check(isinstance(hands, list) and len(hands) == 2, f"{where}: hands {hands!r}")
    for k, hand in enumerate(hands):
        e = expected_hand(frame.frame, k)
        at = f"{where} hand {k}"
        for key in ("hand_id", "handedness", "handedness_confidence", "state", "energy", "optimize_ms",
                    "pinch_distance_mm", "pinch_strength"):
            check(getattr(hand, key) == e[key], f"{at}: {key} {getattr(hand, key)} != {e[key]}")
        check(abs(hand.confidence - e["confidence"]) < 1e-7, f"{at}: confidence")
        check(list(hand.params)[:25] == e["params"], f"{at}: params")
        check([list(j) for j in hand.joints_mm] == e["joints_mm"], f"{at}: joints")
        check([list(t) for t in hand.fingertips_mm] == e["fingertips_mm"], f"{at}: fingertips")
        check(list(hand.palm_center_mm) == e["palm_center_mm"], f"{at}: palm centre")
        check(list(hand.palm_normal) == e["palm_normal"], f"{at}: palm normal")
        check(list(hand.hand_scale) == e["hand_scale"], f"{at}: hand scale")
    d = frame.to_dict()
    check([h["handedness"] for h in d["hands"]] == ["right", "left"]
          and [h["hand_id"] for h in d["hands"]] == [1, 2], f"{where}: dict hands")
    check(all(h["state"] in ("tracking", "recovering") and len(h["params"]) == 26 and len(h["joints"]) == 21
              and len(h["fingertips"]) == 5 for h in d["hands"]), f"{where}: dict shape")


def check_filter():
    """PoseFilter: the library's One Euro filter, reached from Python, on a frame's hand."""
    smooth = handtrack.PoseFilter(beta=0.0, min_cutoff_hz=2.0)
    xs = []
    for i, x in enumerate([0.0, 100.0, 100.0]):
        frame = handtrack.Frame()
        frame.epoch, frame.capture_ns, frame.hand_count = 1, 1_000_000_000 + i * 16_666_667, 1
        hand = frame.hand_records[0]
        hand.hand_id, hand.state = 1, 1
        hand.fingertips_mm[1][0] = x
        xs.append(smooth.apply(frame).hands[0].fingertips_mm[1][0])
    check(xs[0] == 0.0 and 0.0 < xs[1] < xs[2] < 100.0, f"smoothed step {xs}")
    check(handtrack.PoseFilter().params.min_cutoff_hz > 0, "defaults")
    for bad in ({"beta": -1.0}, {"min_cutoff_hz": 0.0}):
        try:
            handtrack.PoseFilter(**bad)
            check(False, f"PoseFilter({bad}) must raise")
        except handtrack.HandtrackError:
            pass


def check_gestures():
    """Gestures: per hand, by hand_id; a hand that leaves ends its gestures."""
    gestures = handtrack.Gestures()
    frame = handtrack.Frame()
    frame.hand_count = 1
    hand = frame.hand_records[0]
    hand.hand_id, hand.handedness_code, hand.state = 5, 1, 1
    hand.fingertips_mm[0][0], hand.fingertips_mm[1][0] = 0.0, 10.0  # tips 10 mm apart: a pinch
    states = gestures.update(frame)
    check(len(states) == 1 and states[0]["hand_id"] == 5 and states[0]["handedness"] == "left"
          and states[0]["present"] and states[0]["gestures"]["pinch"]["event"] == "start", f"pinch start {states}")
    frame.hand_count = 0
    states = gestures.update(frame)
    check(len(states) == 1 and states[0]["hand_id"] == 5 and not states[0]["present"]
          and states[0]["gestures"]["pinch"]["event"] == "end", f"the hand left: {states}")


def check_iteration(name, epoch):
    """client.frames() and client.aframes(); arrays where NumPy is, lists where it is not."""
    with handtrack.Client(name) as client:
        frames = []
        for frame in client.frames(timeout=5.0):
            frames.append(frame)
            if len(frames) == 5:
                break
        check(len(frames) == 5 and all(f.epoch == epoch for f in frames), "frames() iterator")
        hand = frames[0].hands[0]
        joints = hand.joints
        if handtrack._np is not None:
            check(getattr(joints, "shape", None) == (21, 3) and hand.fingertips.shape == (5, 3)
                  and hand.pose_params.shape == (26,), f"NumPy arrays: {type(joints)}")
        else:
            check(isinstance(joints, list) and len(joints) == 21 and len(joints[0]) == 3, "lists without NumPy")

        async def collect():
            got = []
            async for frame in client.aframes(timeout=5.0):
                got.append(frame.frame)
                if len(got) == 5:
                    return got
            return got
        numbers = asyncio.run(collect())
        check(len(numbers) == 5 and numbers == sorted(numbers), f"aframes() async iterator: {numbers}")
    print(f"python client: iteration ok, NumPy {'present' if handtrack._np is not None else 'absent'}")


def main():
    if os.environ.get("HANDTRACK_EXPECT_INSTALLED"):
        root = os.path.realpath(os.environ["HANDTRACK_EXPECT_INSTALLED"])
        check(os.path.realpath(handtrack.__file__).startswith(root),
              f"the installed package is used: {handtrack.__file__}")
    check_filter()
    check_gestures()
    name = f"ht_py_{os.getpid()}"
    try:
        handtrack.Client(name)
        check(False, "opening a missing segment must raise")
    except handtrack.HandtrackError as e:
        check(e.status == -2 and name in str(e), f"missing segment error: {e}")
    started = time.monotonic()
    try:
        handtrack.Client.wait_for(name, timeout=0.3)
        check(False, "wait_for a segment that never comes must raise")
    except handtrack.HandtrackError as e:
        waited = time.monotonic() - started
        check(e.status == handtrack.ERR_NOT_FOUND and waited >= 0.3, f"wait_for: {e} after {waited:.2f} s")

    writer = subprocess.Popen([os.environ["IPC_TEST_WRITER"], "--name", name, "--rate-hz", "500",
                               "--capacity", "64"], stdout=subprocess.PIPE, text=True)
    try:
        ready = writer.stdout.readline().split()
        check(ready[:1] == ["ready"], f"writer did not start: {ready}")
        epoch = int(ready[1])
        with handtrack.Client(name) as client:
            status = client.status()
            check(status.alive == 1 and status.epoch == epoch and status.capacity == 64,
                  "writer status")
            frames = []
            deadline = time.monotonic() + 10
            while len(frames) < 100 and time.monotonic() < deadline:
                frame = client.wait_next(timeout=1.0)
                check(frame is not None, "wait_next returned a frame")
                if frame is None:
                    break
                check_frame(frame, epoch)
                frames.append(frame.frame)
            check(len(frames) == 100, f"read {len(frames)} frames")
            check_iteration(name, epoch)
            check(frames == list(range(frames[0], frames[0] + len(frames))) or client.missed_total > 0,
                  "in order, or the skips were counted")
            latest = client.latest()
            check(latest is not None and latest.frame >= frames[-1], "latest")
            # The example script runs against the same writer.
            example = subprocess.run([sys.executable, os.environ["HANDTRACK_EXAMPLE"],
                                      "--shm-name", name, "--count", "3"],
                                     capture_output=True, text=True, timeout=30)
            check(example.returncode == 0 and example.stdout.count("frame ") == 3
                  and example.stdout.count(" right ") == 3 and example.stdout.count(" left ") == 3,
                  f"example: {example.returncode} {example.stdout!r} {example.stderr!r}")
            gestures = subprocess.run([sys.executable, os.path.join(os.path.dirname(os.environ["HANDTRACK_EXAMPLE"]),
                                                                    "gestures_async.py"),
                                       "--shm-name", name, "--seconds", "1"],
                                      capture_output=True, text=True, timeout=30)
            check(gestures.returncode == 0, f"gestures example: {gestures.returncode} {gestures.stderr!r}")
            writer.terminate()
            writer.wait(timeout=10)
            # The writer marked the segment stopped: the client says so instead of waiting.
            frame = client.wait_next(timeout=2.0)
            while frame is not None:
                frame = client.wait_next(timeout=2.0)
            check(client.trouble == handtrack.ERR_WRITER_STOPPED, f"trouble {client.trouble}")
    finally:
        if writer.poll() is None:
            writer.kill()
        try:
            os.unlink(f"/dev/shm/{name}")
        except FileNotFoundError:
            pass
    print(f"python client: {len(failures)} failed checks")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
