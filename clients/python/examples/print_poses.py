#!/usr/bin/env python3
"""Print the index fingertip and pinch of live poses from handtrackd (Python example).

    print_poses.py [--shm-name NAME] [--count N]
"""
import argparse
import sys

import handtrack


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shm-name", default="handtrack")
    parser.add_argument("--count", type=int, default=10)
    args = parser.parse_args()
    try:
        client = handtrack.Client(args.shm_name)
    except handtrack.HandtrackError as e:
        print(f"print_poses.py: {e}", file=sys.stderr)
        return 1
    with client:
        printed = 0
        while printed < args.count:
            pose = client.wait_next(timeout=2.0)
            if pose is None:
                if client.trouble:
                    print("print_poses.py: daemon not alive, waiting", file=sys.stderr)
                    continue
                print("print_poses.py: no pose for 2 s", file=sys.stderr)
                return 1
            x, y, z = pose.fingertips_mm[1]
            print(f"frame {pose.frame} {pose.state_name:10s} index tip {x:7.1f} {y:7.1f} {z:7.1f} mm"
                  f"  pinch {pose.pinch_distance_mm:5.1f} mm  missed {client.missed}")
            printed += 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
