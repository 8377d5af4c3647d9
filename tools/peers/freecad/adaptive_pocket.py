#!/usr/bin/env python3
"""Run FreeCAD's Adaptive clearing (libarea `area.Adaptive2d`) on a pocket.

Usage: adaptive_pocket.py IN.json OUT.json

IN.json:  {"outer": [[x, y], ...], "tool_diameter": D, "stepover": s, "finish_stepover": f}
OUT.json: {"points": [[x, y], ...],        # tool-centre path, all moves in order, one polyline
           "cutting_length": mm, "link_length": mm, "regions": n, "motion_types": [...],
           "helix_center": [x, y], "helix_radius": r}   # the first region's entry helix
           (FreeCAD's PathAdaptive.py ramps down a helix about HelixCenterPoint through
           StartPoint; it is not in "points")

The library comes from Debian's libfreecad-python3-0.20, unpacked by setup.sh into
$HOME/.cache/thinplan-freecad (override with THINPLAN_FREECAD). libarea-native.so is loaded
with RTLD_GLOBAL first so no LD_LIBRARY_PATH is needed.

Settings as FreeCAD's Path Adaptive operation uses them (PathAdaptive.py, 0.20):
stepOverFactor = stepover / tool, ClearingInside, a finishing profile pass, helix ramp of
the tool diameter (the ramp itself is not part of the output, as our paths have none either),
keepToolDownDistRatio 3, tolerance 0.1 (FreeCAD's default "Accuracy vs performance" value).
"""
import ctypes
import json
import math
import os
import sys

base = os.environ.get("THINPLAN_FREECAD", os.path.expanduser("~/.cache/thinplan-freecad"))
lib = os.path.join(base, "usr/lib/freecad-python3/lib")
ctypes.CDLL(os.path.join(lib, "libarea-native.so"), mode=ctypes.RTLD_GLOBAL)
sys.path.insert(0, lib)
import area  # noqa: E402


def main():
    inp, outp = sys.argv[1], sys.argv[2]
    with open(inp) as fh:
        cfg = json.load(fh)
    outer = [(float(x), float(y)) for x, y in cfg["outer"]]
    d = float(cfg["tool_diameter"])
    xs = [p[0] for p in outer]
    ys = [p[1] for p in outer]
    m = 2 * d
    stock = [
        (min(xs) - m, min(ys) - m),
        (max(xs) + m, min(ys) - m),
        (max(xs) + m, max(ys) + m),
        (min(xs) - m, max(ys) + m),
    ]
    a2d = area.Adaptive2d()
    a2d.toolDiameter = d
    a2d.stepOverFactor = float(cfg["stepover"]) / d
    a2d.helixRampDiameter = d
    a2d.keepToolDownDistRatio = 3.0
    a2d.stockToLeave = 0.0
    a2d.tolerance = float(cfg.get("tolerance", 0.1))
    a2d.forceInsideOut = False
    a2d.finishingProfile = True
    a2d.opType = area.AdaptiveOperationType.ClearingInside
    results = a2d.Execute([stock], [outer], lambda paths: False)
    pts = []
    types = []
    helix_center = None
    helix_radius = None
    cut = 0.0
    link = 0.0
    for region in results:
        if helix_center is None:
            hc = region.HelixCenterPoint
            sp = region.StartPoint
            helix_center = [float(hc[0]), float(hc[1])]
            helix_radius = math.dist(helix_center, (float(sp[0]), float(sp[1])))
        for mtype, path in region.AdaptivePaths:
            mt = int(mtype)
            seg = [(float(p[0]), float(p[1])) for p in path]
            if not seg:
                continue
            for i, p in enumerate(seg):
                if pts:
                    step = math.dist(pts[-1], p)
                    if mt == 0 and i > 0:
                        cut += step
                    else:
                        link += step
                pts.append(p)
            types.append(mt)
    with open(outp, "w") as fh:
        json.dump(
            {
                "points": pts,
                "cutting_length": cut,
                "link_length": link,
                "regions": len(results),
                "motion_types": sorted(set(types)),
                "helix_center": helix_center,
                "helix_radius": helix_radius,
            },
            fh,
        )


if __name__ == "__main__":
    main()
