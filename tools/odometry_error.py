#!/usr/bin/python3
"""The robot's own pose track against the simulator's truth (docs/ROBOT.md, "Odometry drift").

  crunch-virtual-robot --scene S --truth-csv truth.csv -- crunchhost --robot ... --out OUT
  crunchhost export --format csv --in OUT/recording.crec --out CSV
  tools/odometry_error.py truth.csv CSV/odometry.csv [--every 30]

Both files carry CLOCK_MONOTONIC nanoseconds (the harness's when it simulated a pose, the host's
when it read a Create packet), so each odometry row is compared with the truth interpolated at
its own time. Prints the position and heading error every --every seconds and their worst and
final values. Exit status 0; 2 for unreadable input.
"""
import argparse
import bisect
import csv
import math
import sys


def read(path, columns):
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"odometry_error.py: cannot read {path}: {e.strerror}")
    if not rows or any(c not in rows[0] for c in columns):
        sys.exit(f"odometry_error.py: {path}: expected the columns {', '.join(columns)}")
    return [[float(r[c]) for c in columns] for r in rows]


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("truth")
    ap.add_argument("odometry")
    ap.add_argument("--every", type=float, default=30.0, help="seconds between printed rows")
    a = ap.parse_args()
    truth = read(a.truth, ["t_ns", "x_m", "y_m", "theta_rad"])
    odo = read(a.odometry, ["t_ns", "x_m", "y_m", "theta_rad"])
    times = [t[0] for t in truth]
    t0 = odo[0][0]
    worst_p = worst_h = 0.0
    next_print = 0.0
    last = None
    print("t_s     position_error_m  heading_error_deg")
    for t_ns, x, y, th in odo:
        i = bisect.bisect_left(times, t_ns)
        if i == 0 or i >= len(times):
            continue
        (ta, xa, ya, ha), (tb, xb, yb, hb) = truth[i - 1], truth[i]
        f = (t_ns - ta) / (tb - ta) if tb > ta else 0.0
        tx, ty = xa + f * (xb - xa), ya + f * (yb - ya)
        tth = ha + f * (hb - ha)
        ep = math.hypot(x - tx, y - ty)
        eh = math.degrees(wrap(th - tth))
        worst_p, worst_h = max(worst_p, ep), max(worst_h, abs(eh))
        s = (t_ns - t0) * 1e-9
        last = (s, ep, eh)
        if s >= next_print:
            print(f"{s:7.1f} {ep:12.4f} {eh:16.2f}")
            next_print += a.every
    if last is None:
        sys.exit("odometry_error.py: the two files share no time span (same machine, same run?)")
    print(f"final {last[0]:.1f} s: {last[1]:.4f} m, {last[2]:.2f} deg; "
          f"worst {worst_p:.4f} m, {worst_h:.2f} deg")


if __name__ == "__main__":
    main()
