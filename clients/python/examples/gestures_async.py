#!/usr/bin/env python3
"""Gesture events from asyncio code: smoothed poses from handtrackd, pinch/grab/point starts and
ends printed as JSON lines (docs/GESTURES.md, docs/FILTER.md).

    python3 gestures_async.py [--shm-name NAME] [--seconds S]
"""
import argparse
import asyncio
import json

import handtrack


async def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shm-name", default="handtrack")
    parser.add_argument("--seconds", type=float, default=0, help="stop after S seconds (0: never)")
    args = parser.parse_args()
    smooth = handtrack.PoseFilter()
    gestures = handtrack.Gestures()
    loop = asyncio.get_running_loop()
    stop_at = loop.time() + args.seconds if args.seconds > 0 else None
    with handtrack.Client(args.shm_name) as client:
        async for pose in client.aposes(timeout=5.0):
            for name, g in gestures.update(smooth.apply(pose)).items():
                if g["event"]:
                    print(json.dumps({"frame": pose.frame, "gesture": name, "event": g["event"],
                                      "strength": round(g["strength"], 3)}), flush=True)
            if stop_at is not None and loop.time() >= stop_at:
                break


if __name__ == "__main__":
    asyncio.run(main())
