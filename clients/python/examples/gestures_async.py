#!/usr/bin/env python3
"""Gesture events from asyncio code: smoothed frames from handtrackd, each hand's pinch/grab/point
starts and ends printed as JSON lines (docs/GESTURES.md, docs/FILTER.md).

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
        async for frame in client.aframes(timeout=5.0):
            for hand in gestures.update(smooth.apply(frame)):
                for name, g in hand["gestures"].items():
                    if g["event"]:
                        print(json.dumps({"frame": frame.frame, "hand_id": hand["hand_id"],
                                          "handedness": hand["handedness"], "gesture": name,
                                          "event": g["event"], "strength": round(g["strength"], 3)}),
                              flush=True)
            if stop_at is not None and loop.time() >= stop_at:
                break


if __name__ == "__main__":
    asyncio.run(main())
