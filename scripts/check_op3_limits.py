"""Print the self-collision clearance of the bundled OP3 at its joint limits.

For each hinge: the closest robot-robot approach while that joint alone sweeps from the nominal
posture to its lower and to its upper limit; then every same-limb pair's limit-box corner that
comes within --report mm. With --extents, also how far each joint could move from nominal before
the shells touch (the figures quoted in robots/op3/op3.toml's reasons).

    python scripts/check_op3_limits.py [--robot op3] [--report 5] [--extents]

Exit status 1 when any probe penetrates deeper than --tolerance mm (default 1).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from motion2robot.robot.limit_check import check_limits, free_extent, hinge_names
from motion2robot.robot.loader import load_robot


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", default="op3")
    ap.add_argument("--report", type=float, default=5.0, help="list corners closer than this (mm)")
    ap.add_argument("--tolerance", type=float, default=1.0, help="allowed penetration (mm)")
    ap.add_argument("--extents", action="store_true", help="also print the collision-free extent of each joint")
    args = ap.parse_args(argv)

    robot = load_robot(args.robot)
    model = robot.model
    nominal = dict(robot.config.nominal)
    probes = check_limits(model, nominal)

    def mm(x: float) -> str:
        return f"{x * 1000:+7.1f}"

    print(f"robot {robot.name}: clearance (mm, negative = penetration; capped at +20) at the limits")
    print(f"{'joint':<13} {'nominal':>8} {'lower':>8} {'upper':>8} {'sweep->lo':>10} {'sweep->hi':>10}  closest pair")
    sweeps = {(p.label.split()[0], p.label.split()[2]): p for p in probes if p.kind == "sweep"}
    for n in hinge_names(model):
        lo, hi = model.joint(n).range
        a, b = sweeps[(n, "lower")], sweeps[(n, "upper")]
        worst = a if a.min_distance <= b.min_distance else b
        pair = " / ".join(worst.pair) if worst.pair else "-"
        print(f"{n:<13} {nominal.get(n, 0.0):+8.3f} {lo:+8.3f} {hi:+8.3f} {mm(a.min_distance):>10} {mm(b.min_distance):>10}  {pair}")

    corners = [p for p in probes if p.kind == "corner"]
    close = sorted((p for p in corners if p.min_distance * 1000 < args.report), key=lambda p: p.min_distance)
    print(f"\n{len(corners)} same-limb limit-box corners; minimum clearance {mm(min(p.min_distance for p in corners))} mm;"
          f" {len(close)} closer than {args.report:g} mm:")
    for p in close:
        print(f"  {mm(p.min_distance)}  {p.label}  ({' / '.join(p.pair) if p.pair else '-'})")

    if args.extents:
        print("\ncollision-free extent from nominal (rad, 0.01 steps, up to +-pi):")
        for n in hinge_names(model):
            lo, lp = free_extent(model, nominal, n, -np.pi)
            hi, hp = free_extent(model, nominal, n, np.pi)
            print(f"  {n:<13} {lo:+7.3f} ({' / '.join(lp) if lp else 'free'})   {hi:+7.3f} ({' / '.join(hp) if hp else 'free'})")

    worst = min(p.min_distance for p in probes)
    print(f"\nworst clearance over {len(probes)} probes: {mm(worst)} mm (tolerance -{args.tolerance:g} mm)")
    return 0 if worst * 1000 >= -args.tolerance else 1


if __name__ == "__main__":
    sys.exit(main())
