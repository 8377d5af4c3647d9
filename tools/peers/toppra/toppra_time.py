#!/usr/bin/env python3
"""Time-optimal traversal time of tool paths by TOPP-RA (the peer of crates/feeds).

Usage:
    python toppra_time.py PATHS.json [--grid-factor F] [--min-grid N]

PATHS.json:
    {"paths": [{"name": "circle", "points": [[x, y, z], ...],
                "v_max": [vx, vy, vz], "a_max": [ax, ay, az]}, ...]}
    (mm, mm/s, mm/s^2)

For every path: the geometric path is a cubic spline through the points parameterised by
their cumulative chord length s (scipy CubicSpline through toppra.SplineInterpolator;
'periodic' end conditions when the path is closed, else 'not-a-knot'). Constraints: per-axis
velocity |q'(s) sd| <= V (JointVelocityConstraint) and per-axis acceleration
|q'(s) sdd + q''(s) sd^2| <= A (JointAccelerationConstraint). Rest to rest (sd = 0 at both
ends). The gridpoints are uniform in s, max(min_grid, grid_factor * number of points).

Discretisation: 'collocation' by default (constraints at each gridpoint with its own
sd^2, sdd), because toppra's own default 'interpolation' scheme fails with "controllable set
can't be computed" (seidel solver) on paths where a straight line meets an arc (rounded
pentagon, rounded zigzag). Collocation is slightly optimistic at a finite grid (the time
grows towards the continuous optimum as the grid is refined), so a ratio ours/TOPP-RA
measured against it is, if anything, pessimistic for us. '--scheme interpolation' selects
the other one. Nothing else: no centripetal
cap, no feed cap, no corner stops (TOPP-RA has no notion of them).

Same geometry on both sides: a polyline and the cubic spline through its points are not the
same path (the spline overshoots where the spacing or the curvature jumps, and a three-point
curvature does not see what it does between the points; on the slot spirals of the pocket
bench the two differ by 15 % in time). With '--resample K' every result also carries
"resampled": the spline sampled at K points per input segment, uniformly in its parameter, so
that the caller can time the very curve TOPP-RA timed.

Prints JSON: {"toppra_version": ..., "results": [{"name", "time", "gridpoints", "length",
"solve_s"[, "resampled"]}]} on stdout. The time is the sum over grid intervals of 2*ds/(sd_i + sd_{i+1}),
which is how toppra's constant-acceleration parametriser times the trajectory.
"""

import argparse
import json
import sys
import time
from importlib.metadata import version

import numpy as np
import toppra
import toppra.algorithm as algo
import toppra.constraint as constraint

toppra.setup_logging("WARNING")


def solve(points, v_max, a_max, grid_factor, min_grid, scheme, resample=0):
    pts = np.asarray(points, dtype=float)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    keep = np.concatenate([[True], seg > 1e-9])  # drop repeated points
    pts = pts[keep]
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    ss = np.concatenate([[0.0], np.cumsum(seg)])
    closed = np.linalg.norm(pts[0] - pts[-1]) < 1e-6 * max(ss[-1], 1.0)
    if closed:
        pts[-1] = pts[0]
    path = toppra.SplineInterpolator(ss, pts, bc_type="periodic" if closed else "not-a-knot")
    dof = pts.shape[1]
    vlim = np.array([[-v, v] for v in v_max[:dof]])
    alim = np.array([[-a, a] for a in a_max[:dof]])
    cons = [
        constraint.JointVelocityConstraint(vlim),
        constraint.JointAccelerationConstraint(alim, discretization_scheme=scheme),
    ]
    n_grid = max(min_grid, int(grid_factor * len(pts)))
    grid = np.linspace(0.0, ss[-1], n_grid)
    inst = algo.TOPPRA(cons, path, gridpoints=grid, solver_wrapper="seidel")
    t0 = time.perf_counter()
    sdd, sd, v, K = inst.compute_parameterization(0.0, 0.0, return_data=True)
    solve_s = time.perf_counter() - t0
    res = None
    if resample > 0:
        m = int(resample) * (len(ss) - 1) + 1
        res = path(np.linspace(0.0, ss[-1], m)).tolist()
    if sd is None or np.any(np.isnan(sd)):
        return None, n_grid, ss[-1], solve_s, res
    sd = np.maximum(np.asarray(sd, dtype=float), 0.0)
    ds = np.diff(grid)
    denom = sd[:-1] + sd[1:]
    t = float(np.sum(2.0 * ds / denom))
    return t, n_grid, float(ss[-1]), solve_s, res


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("paths_json")
    ap.add_argument("--grid-factor", type=float, default=8.0,
                    help="gridpoints per input point (default 8)")
    ap.add_argument("--min-grid", type=int, default=4000)
    ap.add_argument("--scheme", choices=["collocation", "interpolation"], default="collocation")
    ap.add_argument("--resample", type=int, default=0,
                    help="also return the spline sampled at K points per input segment")
    args = ap.parse_args()
    with open(args.paths_json) as f:
        data = json.load(f)
    scheme = {"collocation": constraint.DiscretizationType.Collocation,
              "interpolation": constraint.DiscretizationType.Interpolation}[args.scheme]
    out = []
    for p in data["paths"]:
        t, n, length, solve_s, res = solve(p["points"], p["v_max"], p["a_max"],
                                           args.grid_factor, args.min_grid, scheme, args.resample)
        r = {"name": p["name"], "time": t, "gridpoints": n, "length": length, "solve_s": solve_s}
        if res is not None:
            r["resampled"] = res
        out.append(r)
        print(f"[toppra] {p['name']}: {t} s ({n} gridpoints, {solve_s:.2f} s)", file=sys.stderr)
    json.dump({"toppra_version": version("toppra"), "scheme": args.scheme, "results": out}, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
