#!/usr/bin/env python3
"""Where the closed loop's collisions are: how small the target lane's slot
(the follower's front to the target's rear, moved as the scene's traffic
model moves them, ignoring the ego) gets within the run, for the rollouts
that collided and for the successes. docs/closed_loop.md, "Backing out".

    lanechange sample --count N --seed S --out SCENES
    lanechange evaluate --count N --seed S --planner miqp --out RUN
    scripts/collision_slots.py RUN/rollouts.csv SCENES [--planner miqp]
"""
import argparse
import csv
import json
import sys
from pathlib import Path

SETTLE_SECONDS = 3.0  # closed_loop.settle_time's default: the run is the horizon and this
STEP = 0.1
THRESHOLDS = (10.0, 15.0, 20.0, 25.0)


def position(car, t):
    """Constant acceleration, stopping at 0 m/s (the traffic models' own rule)."""
    x, v, a = car["x"], car["v"], car.get("a", 0.0)
    if a < 0 and v + a * t < 0:
        t = -v / a
    return x + v * t + 0.5 * a * t * t


def smallest_slot(scene):
    """None for IDM scenes, whose cars react, so no slot is predicted."""
    if scene["behavior"] == "idm":
        return None
    length = scene["vehicle"]["length"]
    steps = int(round((scene["horizon"] + SETTLE_SECONDS) / STEP))
    return min(
        position(scene["target"], k * STEP) - position(scene["follower"], k * STEP) - length
        for k in range(steps + 1)
    )


def fail(message):
    print(f"collision_slots: {message}", file=sys.stderr)
    sys.exit(2)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rollouts", type=Path)
    parser.add_argument("scenes", type=Path)
    parser.add_argument("--planner", default="miqp")
    args = parser.parse_args()
    try:
        rows = [r for r in csv.DictReader(open(args.rollouts)) if r["planner"] == args.planner]
    except (OSError, KeyError) as error:
        fail(f"cannot read {args.rollouts}: {error}")
    if not rows:
        fail(f"no rollouts of {args.planner} in {args.rollouts}")
    collided, succeeded = [], []
    for row in rows:
        path = args.scenes / f"scenario_{int(row['index']):06d}.json"
        try:
            slot = smallest_slot(json.load(open(path)))
        except (OSError, ValueError, KeyError) as error:
            fail(f"{path}: {error}")
        if slot is None:
            continue
        if row["collision"] == "1":
            collided.append(slot)
        elif row["outcome"] == "well_posed":
            succeeded.append(slot)
    total_collisions = sum(r["collision"] == "1" for r in rows)
    print(f"{args.planner}: {total_collisions} collisions, {len(collided)} outside the IDM scenes; "
          f"{len(succeeded)} successes outside them")
    print("| smallest slot within the run below | collisions | successes |")
    print("|---|---|---|")
    for threshold in THRESHOLDS:
        print(f"| {threshold:g} m | {sum(s < threshold for s in collided)} | "
              f"{sum(s < threshold for s in succeeded)} |")


if __name__ == "__main__":
    main()
