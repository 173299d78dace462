#!/usr/bin/env python3
"""Print every hand of live frames from handtrackd: id, handedness, index fingertip, pinch (Python example).

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
            frame = client.wait_next(timeout=2.0)
            if frame is None:
                if client.trouble:
                    print("print_poses.py: daemon not alive, waiting", file=sys.stderr)
                    continue
                print("print_poses.py: no frame for 2 s", file=sys.stderr)
                return 1
            hands = [f"hand {hand.hand_id} {hand.handedness} {hand.state_name} index tip "
                     f"{hand.fingertips_mm[1][0]:.1f} {hand.fingertips_mm[1][1]:.1f} {hand.fingertips_mm[1][2]:.1f} mm"
                     f" pinch {hand.pinch_distance_mm:.1f} mm" for hand in frame.hands]
            print(f"frame {frame.frame} (missed {client.missed}): " + ("; ".join(hands) or "no hand"))
            printed += 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
