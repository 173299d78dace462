#!/usr/bin/env python3
"""The Python module reads real records from a real writer process, field by field.

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


def checksum(pose):
    """FNV-1a 32 of the record with epoch, publish_ns and params[25] zeroed (test_pattern.hpp)."""
    copy = handtrack.Pose.from_buffer_copy(bytes(pose))
    copy.epoch = 0
    copy.publish_ns = 0
    copy.params[25] = 0.0
    h = 2166136261
    for b in bytes(copy):
        h = ((h ^ b) * 16777619) & 0xFFFFFFFF
    return h


def expected_record(frame):
    """make_test_record() of tests/ipc/test_pattern.hpp, in Python."""
    f = float(frame % 1000)
    base = float(frame % 4096)
    return {
        "capture_ns": frame * 1000 + 7,
        "grab_ms": f * 0.25, "preprocess_ms": f * 0.25 + 1, "optimize_ms": f * 0.25 + 2,
        "publish_ms": f * 0.25 + 3,
        "state": frame % 3, "confidence": (frame % 100) / 128.0, "energy": f * 0.5,
        "params": [frame + k * 0.5 for k in range(25)],
        "joints_mm": [[base + j * 3 + a for a in range(3)] for j in range(21)],
        "fingertips_mm": [[base + 100 + t * 3 + a for a in range(3)] for t in range(5)],
        "palm_center_mm": [base + 200 + a for a in range(3)],
        "palm_normal": [0.0, 0.0, -1.0],
        "pinch_distance_mm": (frame % 256) * 0.5, "pinch_strength": (frame % 4) * 0.25,
        "hand_scale": [1.0 + (frame % 8) * 0.125, 1.25, 0.75],
    }


def check_pose(pose, epoch):
    e = expected_record(pose.frame)
    where = f"frame {pose.frame}"
    check(pose.epoch == epoch, f"{where}: epoch {pose.epoch} != {epoch}")
    check(pose.publish_ns > 0, f"{where}: publish_ns not stamped")
    for key in ("capture_ns", "grab_ms", "preprocess_ms", "optimize_ms", "publish_ms", "state",
                "energy", "pinch_distance_mm", "pinch_strength"):
        check(getattr(pose, key) == e[key], f"{where}: {key} {getattr(pose, key)} != {e[key]}")
    check(abs(pose.confidence - e["confidence"]) < 1e-7, f"{where}: confidence")
    check(list(pose.params)[:25] == e["params"], f"{where}: params")
    check(pose.params[25] == float(checksum(pose)), f"{where}: checksum")
    check([list(j) for j in pose.joints_mm] == e["joints_mm"], f"{where}: joints")
    check([list(t) for t in pose.fingertips_mm] == e["fingertips_mm"], f"{where}: fingertips")
    check(list(pose.palm_center_mm) == e["palm_center_mm"], f"{where}: palm centre")
    check(list(pose.palm_normal) == e["palm_normal"], f"{where}: palm normal")
    check(list(pose.hand_scale) == e["hand_scale"], f"{where}: hand scale")
    d = pose.to_dict()
    check(d["state"] in ("no_hand", "tracking", "recovering"), f"{where}: state name")
    check(len(d["params"]) == 26 and len(d["joints"]) == 21 and len(d["fingertips"]) == 5,
          f"{where}: dict shape")


def check_filter():
    """PoseFilter: the library's One Euro filter, reached from Python."""
    smooth = handtrack.PoseFilter(beta=0.0, min_cutoff_hz=2.0)
    poses = []
    for i, x in enumerate([0.0, 100.0, 100.0]):
        pose = handtrack.Pose()
        pose.epoch, pose.state, pose.capture_ns = 1, 1, 1_000_000_000 + i * 16_666_667
        pose.fingertips_mm[1][0] = x
        poses.append(smooth.apply(pose).fingertips_mm[1][0])
    check(poses[0] == 0.0 and 0.0 < poses[1] < poses[2] < 100.0, f"smoothed step {poses}")
    check(handtrack.PoseFilter().params.min_cutoff_hz > 0, "defaults")
    for bad in ({"beta": -1.0}, {"min_cutoff_hz": 0.0}):
        try:
            handtrack.PoseFilter(**bad)
            check(False, f"PoseFilter({bad}) must raise")
        except handtrack.HandtrackError:
            pass


def check_iteration(name, epoch):
    """client.poses() and client.aposes(); arrays where NumPy is, lists where it is not."""
    with handtrack.Client(name) as client:
        poses = []
        for pose in client.poses(timeout=5.0):
            poses.append(pose)
            if len(poses) == 5:
                break
        check(len(poses) == 5 and all(p.epoch == epoch for p in poses), "poses() iterator")
        joints = poses[0].joints
        if handtrack._np is not None:
            check(getattr(joints, "shape", None) == (21, 3) and poses[0].fingertips.shape == (5, 3)
                  and poses[0].pose_params.shape == (26,), f"NumPy arrays: {type(joints)}")
        else:
            check(isinstance(joints, list) and len(joints) == 21 and len(joints[0]) == 3, "lists without NumPy")

        async def collect():
            got = []
            async for pose in client.aposes(timeout=5.0):
                got.append(pose.frame)
                if len(got) == 5:
                    return got
            return got
        frames = asyncio.run(collect())
        check(len(frames) == 5 and frames == sorted(frames), f"aposes() async iterator: {frames}")
    print(f"python client: iteration ok, NumPy {'present' if handtrack._np is not None else 'absent'}")


def main():
    if os.environ.get("HANDTRACK_EXPECT_INSTALLED"):
        root = os.path.realpath(os.environ["HANDTRACK_EXPECT_INSTALLED"])
        check(os.path.realpath(handtrack.__file__).startswith(root),
              f"the installed package is used: {handtrack.__file__}")
    check_filter()
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
                pose = client.wait_next(timeout=1.0)
                check(pose is not None, "wait_next returned a pose")
                if pose is None:
                    break
                check_pose(pose, epoch)
                frames.append(pose.frame)
            check(len(frames) == 100, f"read {len(frames)} poses")
            check_iteration(name, epoch)
            check(frames == list(range(frames[0], frames[0] + len(frames))) or client.missed_total > 0,
                  "in order, or the skips were counted")
            latest = client.latest()
            check(latest is not None and latest.frame >= frames[-1], "latest")
            # The example script runs against the same writer.
            example = subprocess.run([sys.executable, os.environ["HANDTRACK_EXAMPLE"],
                                      "--shm-name", name, "--count", "3"],
                                     capture_output=True, text=True, timeout=30)
            check(example.returncode == 0 and example.stdout.count("frame ") == 3,
                  f"example: {example.returncode} {example.stdout!r} {example.stderr!r}")
            gestures = subprocess.run([sys.executable, os.path.join(os.path.dirname(os.environ["HANDTRACK_EXAMPLE"]),
                                                                    "gestures_async.py"),
                                       "--shm-name", name, "--seconds", "1"],
                                      capture_output=True, text=True, timeout=30)
            check(gestures.returncode == 0, f"gestures example: {gestures.returncode} {gestures.stderr!r}")
            writer.terminate()
            writer.wait(timeout=10)
            # The writer marked the segment stopped: the client says so instead of waiting.
            pose = client.wait_next(timeout=2.0)
            while pose is not None:
                pose = client.wait_next(timeout=2.0)
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
