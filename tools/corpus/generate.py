#!/usr/bin/env python3
"""Generate a corpus of thin-walled 2.5D test parts as STEP files (OpenCASCADE via OCP),
each with ground-truth labels written from the construction parameters.

    generate.py OUT_DIR [--seed N] [--only NAME[,NAME...]] [--check] [--list]

Writes OUT_DIR/NAME.step (AP214, mm, one solid), OUT_DIR/NAME.labels.json and
OUT_DIR/index.json. Every part sits on z=0 with its web/floor at the bottom and is
machinable from +Z. See tools/corpus/README.md for the families and the label schema.

Construction is subtractive: a block (or an extruded cross-section) minus pocket tools
(prisms of filleted 2D outlines, whose bottom loop is filleted with
BRepFilletAPI_MakeFillet for floor fillets), holes, slots and cut-outs, in one
BRepAlgoAPI_Cut, then ShapeUpgrade_UnifySameDomain. Labels never come from measuring
the result, except `volume` (OCC GProp of the written solid).
"""
import argparse
import json
import math
import os
import random
import re
import sys
import time

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import (BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace,
                                BRepBuilderAPI_MakeWire)
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepGProp import BRepGProp
from OCP.BRepPrimAPI import (BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder,
                             BRepPrimAPI_MakePrism)
from OCP.Bnd import Bnd_Box
from OCP.GC import GC_MakeArcOfCircle
from OCP.GeomAbs import GeomAbs_Plane
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.Message import Message, Message_Gravity
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader, STEPControl_Writer
from OCP.ShapeUpgrade import ShapeUpgrade_UnifySameDomain
from OCP.TCollection import TCollection_HAsciiString
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS
try:  # OCP < 8
    from OCP.TopTools import TopTools_ListOfShape
except ImportError:  # OCP 8: NCollection instances live in OCP.collections
    from OCP.collections import List_TopoDS_Shape as TopTools_ListOfShape
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Vec

try:
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
except ImportError:  # pragma: no cover
    APIHeaderSection_MakeHeader = None

GENERATOR = "thinplan-corpus"
GENERATOR_VERSION = "1.0.0"
DEFAULT_SEED = 2026
STEP_TIMESTAMP = "2026-01-01T00:00:00"
SQ3 = math.sqrt(3.0)

def _cast(kind):
    return getattr(TopoDS, kind + "_s", None) or getattr(TopoDS, kind)


as_face, as_edge, as_solid = _cast("Face"), _cast("Edge"), _cast("Solid")

# Silence OCC's transfer statistics on stdout.
for _p in Message.DefaultMessenger_s().Printers():
    _p.SetTraceLevel(Message_Gravity.Message_Fail)


class PartError(Exception):
    pass


# --------------------------------------------------------------------------- numbers

def q(x, step=0.1):
    """Round to a multiple of step (construction values are 'drawing' numbers)."""
    return round(round(x / step) * step, 6)


def r6(x):
    return round(float(x), 6) + 0.0


def uni(rng, a, b, step=0.1):
    return q(rng.uniform(a, b), step)


# --------------------------------------------------------------------------- 2D outlines

def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1])


def _add(a, b):
    return (a[0] + b[0], a[1] + b[1])


def _mul(a, s):
    return (a[0] * s, a[1] * s)


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1]


def _unit(a):
    n = math.hypot(a[0], a[1])
    return (a[0] / n, a[1] / n)


def fillet_outline(pts, radii):
    """Closed polygon `pts` with a tangent arc of radius radii[i] at vertex i (0 = sharp).
    Works at convex and reflex vertices (the arc lies in the smaller angle).
    Returns a list of segments ('line', p, q) / ('arc', p, mid, q), or None when an
    edge is too short for the tangent lengths of its two end arcs."""
    n = len(pts)
    corners, tlen = [], []
    for i in range(n):
        P, A, B = pts[i], pts[i - 1], pts[(i + 1) % n]
        r = radii[i]
        if r <= 0:
            corners.append((P, None, P))
            tlen.append(0.0)
            continue
        a = _unit(_sub(P, A))
        b = _unit(_sub(B, P))
        c = max(-1.0, min(1.0, -_dot(a, b)))
        phi = math.acos(c)  # the corner's (smaller) angle
        d = r / math.tan(phi / 2)
        t1 = _sub(P, _mul(a, d))
        t2 = _add(P, _mul(b, d))
        bis = _unit(_add(_mul(a, -1.0), b))
        centre = _add(P, _mul(bis, r / math.sin(phi / 2)))
        mid = _sub(centre, _mul(bis, r))
        corners.append((t1, mid, t2))
        tlen.append(d)
    for i in range(n):
        L = math.dist(pts[i], pts[(i + 1) % n])
        if tlen[i] + tlen[(i + 1) % n] > L + 1e-9:
            return None
    segs = []
    for i in range(n):
        t1, mid, t2 = corners[i]
        if mid is not None:
            segs.append(("arc", t1, mid, t2))
        nxt = corners[(i + 1) % n][0]
        if math.dist(t2, nxt) > 1e-7:
            segs.append(("line", t2, nxt))
    return segs


def clip_halfplanes(hps, big=1e5):
    """Convex polygon (ccw) = intersection of half-planes n.x <= c, as a list of points."""
    poly = [(-big, -big), (big, -big), (big, big), (-big, big)]
    for (nx, ny, c) in hps:
        out = []
        m = len(poly)
        for i in range(m):
            P, Q = poly[i], poly[(i + 1) % m]
            fp = nx * P[0] + ny * P[1] - c
            fq = nx * Q[0] + ny * Q[1] - c
            if fp <= 0:
                out.append(P)
            if (fp < 0 < fq) or (fq < 0 < fp):
                t = fp / (fp - fq)
                out.append((P[0] + t * (Q[0] - P[0]), P[1] + t * (Q[1] - P[1])))
        poly = out
        if len(poly) < 3:
            return []
    # merge near-duplicate vertices
    res = []
    for p in poly:
        if not res or math.dist(p, res[-1]) > 1e-7:
            res.append(p)
    if len(res) > 1 and math.dist(res[0], res[-1]) <= 1e-7:
        res.pop()
    # drop vertices on a straight run (redundant half-planes through a vertex)
    changed = True
    while changed and len(res) >= 3:
        changed = False
        for i in range(len(res)):
            a, b = _unit(_sub(res[i], res[i - 1])), _unit(_sub(res[(i + 1) % len(res)], res[i]))
            if abs(a[0] * b[1] - a[1] * b[0]) < 1e-9 and _dot(a, b) > 0:
                res.pop(i)
                changed = True
                break
    return res if len(res) >= 3 else []


def poly_area(p):
    return 0.5 * sum(p[i][0] * p[(i + 1) % len(p)][1] - p[(i + 1) % len(p)][0] * p[i][1]
                     for i in range(len(p)))


def rect(x0, y0, x1, y1):
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


# --------------------------------------------------------------------------- OCC helpers

def wire_from_segments(segs, to3d):
    mk = BRepBuilderAPI_MakeWire()
    for s in segs:
        if s[0] == "line":
            e = BRepBuilderAPI_MakeEdge(to3d(s[1]), to3d(s[2])).Edge()
        else:
            arc = GC_MakeArcOfCircle(to3d(s[1]), to3d(s[2]), to3d(s[3])).Value()
            e = BRepBuilderAPI_MakeEdge(arc).Edge()
        mk.Add(e)
    if not mk.IsDone():
        raise PartError("wire construction failed")
    return mk.Wire()


def prism(segs, to3d, vec):
    face = BRepBuilderAPI_MakeFace(wire_from_segments(segs, to3d), True).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(*vec)).Shape()


def xy_at(z):
    return lambda p: gp_Pnt(p[0], p[1], z)


def is_valid(shape):
    return BRepCheck_Analyzer(shape).IsValid()


def fillet_bottom_loop(solid, z, r):
    """Fillet every edge of the planar face at height z (a pocket tool's bottom loop)."""
    mk = BRepFilletAPI_MakeFillet(solid)
    exp = TopExp_Explorer(solid, TopAbs_FACE)
    face = None
    while exp.More():
        f = as_face(exp.Current())
        s = BRepAdaptor_Surface(f)
        if s.GetType() == GeomAbs_Plane:
            pl = s.Plane()
            if abs(abs(pl.Axis().Direction().Z()) - 1) < 1e-9 and abs(pl.Location().Z() - z) < 1e-7:
                bb = Bnd_Box()
                BRepBndLib.Add_s(f, bb)
                if abs(bb.CornerMax().Z() - z) < 1e-3:
                    face = f
                    break
        exp.Next()
    if face is None:
        return None
    e = TopExp_Explorer(face, TopAbs_EDGE)
    while e.More():
        mk.Add(r, as_edge(e.Current()))
        e.Next()
    try:
        mk.Build()
    except Exception:
        return None
    if not mk.IsDone():
        return None
    out = mk.Shape()
    return out if is_valid(out) else None


def cylinder(x, y, z0, z1, d):
    ax = gp_Ax2(gp_Pnt(x, y, z0), gp_Dir(0, 0, 1))
    return BRepPrimAPI_MakeCylinder(ax, d / 2, z1 - z0).Shape()


def box(x0, y0, z0, x1, y1, z1):
    return BRepPrimAPI_MakeBox(gp_Pnt(x0, y0, z0), gp_Pnt(x1, y1, z1)).Shape()


def single_solid(shape):
    solids = []
    exp = TopExp_Explorer(shape, TopAbs_SOLID)
    while exp.More():
        solids.append(as_solid(exp.Current()))
        exp.Next()
    if len(solids) != 1:
        raise PartError(f"{len(solids)} solids")
    return solids[0]


def shells_closed(shape):
    exp = TopExp_Explorer(shape, TopAbs_SHELL)
    n = 0
    while exp.More():
        n += 1
        if not BRep_Tool.IsClosed_s(exp.Current()):
            return False
        exp.Next()
    return n >= 1


def cut_all(base, tools):
    if not tools:
        shape = base
    else:
        args, tl = TopTools_ListOfShape(), TopTools_ListOfShape()
        args.Append(base)
        for t in tools:
            tl.Append(t)
        op = BRepAlgoAPI_Cut()
        op.SetArguments(args)
        op.SetTools(tl)
        op.SetRunParallel(False)
        op.Build()
        if not op.IsDone():
            raise PartError("boolean cut failed")
        shape = op.Shape()
    u = ShapeUpgrade_UnifySameDomain(shape, True, True, False)
    u.Build()
    solid = single_solid(u.Shape())
    if not is_valid(solid) or not shells_closed(solid):
        raise PartError("result is not a valid closed solid")
    return solid


def volume(shape):
    p = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, p)
    return p.Mass()


def occ_bbox(shape):
    bb = Bnd_Box()
    BRepBndLib.AddOptimal_s(shape, bb, False, False)
    a, b = bb.CornerMin(), bb.CornerMax()
    return [a.X(), a.Y(), a.Z(), b.X(), b.Y(), b.Z()]


def write_step(shape, path, name):
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    # the PRODUCT name (OCC's default carries a per-process counter)
    Interface_Static.SetCVal_s("write.step.product.name", name)
    w = STEPControl_Writer()
    if w.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone:
        raise PartError("STEP transfer failed")
    if APIHeaderSection_MakeHeader is not None:
        h = APIHeaderSection_MakeHeader(w.Model())
        h.SetName(TCollection_HAsciiString(name))
        h.SetTimeStamp(TCollection_HAsciiString(STEP_TIMESTAMP))
        h.SetAuthorValue(1, TCollection_HAsciiString(GENERATOR))
        h.SetOrganizationValue(1, TCollection_HAsciiString("thinplan"))
    tmp = path + ".tmp"
    if w.Write(tmp) != IFSelect_RetDone:
        raise PartError("STEP write failed")
    with open(tmp) as fh:
        text = fh.read()
    # Belt and braces: a fixed header timestamp and product name whatever OCC put there.
    text = re.sub(r"FILE_NAME\('([^']*)','[^']*'", lambda m: f"FILE_NAME('{m.group(1)}','{STEP_TIMESTAMP}'",
                  text, count=1)
    text = re.sub(r"= PRODUCT\('[^']*',\s*'[^']*'", f"= PRODUCT('{name}','{name}'", text, count=1)
    with open(tmp, "w") as fh:
        fh.write(text)
    os.replace(tmp, path)


def read_step(path):
    Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
    r = STEPControl_Reader()
    if r.ReadFile(path) != IFSelect_RetDone:
        raise PartError("STEP read failed")
    r.TransferRoots()
    return r.OneShape()


# --------------------------------------------------------------------------- part builder

class Part:
    """Collects construction parameters, labels and cutting tools for one part."""

    def __init__(self, name, family, variant, seed):
        self.name, self.family, self.variant, self.seed = name, family, variant, seed
        self.rng = random.Random(f"{seed}/{name}")
        self.walls, self.crossings, self.t_joints = [], [], []
        self.holes, self.cutouts, self.slots, self.pockets = [], [], [], []
        self.tools = []
        self.adjust = []  # fillet reductions / skips
        self.corner_radii = []  # every concave radius seen from +Z
        self.vertical_R = None
        self.floor_r = None
        self.bbox = None
        self.base = None
        self.params = {}

    # -- walls
    def wall(self, role, t, h, length, normal, offset, **extra):
        wid = f"W{len(self.walls) + 1}"
        n = list(normal)
        if role != "web":  # canonical sign for vertical walls: nx > 0, or nx == 0 and ny > 0
            if n[0] < -1e-12 or (abs(n[0]) <= 1e-12 and n[1] < 0):
                n = [-n[0], -n[1], -n[2]]
                offset = -offset
        w = {"id": wid, "role": role, "thickness": r6(t), "height": r6(h), "length": r6(length),
             "normal": [r6(c) for c in n], "plane_offset": r6(offset)}
        w.update(extra)
        self.walls.append(w)
        return wid

    # -- pocket tools
    def pocket(self, poly, R, z_floor, z_top, floor_r, depth, closed=True, floor_wall=None,
               label=True, extra=None):
        """Cut a pocket whose sharp outline is the convex polygon `poly` (ccw), corner
        radius R (reduced in 0.5 steps if the outline is too small), floor fillet floor_r."""
        R_used = R
        segs = fillet_outline(poly, [R_used] * len(poly))
        while segs is None and R_used > 1.0:
            R_used = q(R_used - 0.5, 0.5)
            segs = fillet_outline(poly, [R_used] * len(poly))
        if segs is None:
            raise PartError("pocket outline too small")
        if R_used != R:
            self.adjust.append({"what": "vertical_corner_radius", "pocket": len(self.pockets) + 1,
                                "from": R, "to": R_used})
        tool = prism(segs, xy_at(z_floor), (0, 0, z_top - z_floor))
        fr_used = None
        if floor_r:
            cand = min(floor_r, q(R_used - 0.5, 0.5)) if R_used > 1.0 else 0
            tried = []
            for rr in (cand, q(cand * 0.5, 0.5)):
                if rr <= 0 or rr in tried:
                    continue
                tried.append(rr)
                ft = fillet_bottom_loop(tool, z_floor, rr)
                if ft is not None:
                    tool, fr_used = ft, rr
                    break
            if fr_used != floor_r:
                self.adjust.append({"what": "floor_fillet", "pocket": len(self.pockets) + 1,
                                    "from": floor_r, "to": fr_used})
        self.tools.append(tool)
        self.corner_radii.append(R_used)
        if label:
            pk = {"id": f"P{len(self.pockets) + 1}", "closed": closed, "depth": r6(depth),
                  "floor_z": r6(z_floor), "corner_radius": r6(R_used),
                  "floor_fillet": None if fr_used is None else r6(fr_used),
                  "polygon": [[r6(x), r6(y)] for (x, y) in poly]}
            if floor_wall:
                pk["floor_wall"] = floor_wall
            if extra:
                pk.update(extra)
            self.pockets.append(pk)
        return R_used, fr_used

    def hole(self, x, y, z_top, d):
        self.tools.append(cylinder(x, y, -1.0, z_top + 0.5, d))
        self.corner_radii.append(d / 2)
        self.holes.append({"diameter": r6(d), "center": [r6(x), r6(y), r6(z_top)],
                           "axis": [0, 0, 1], "through": True})

    def slot(self, x, y, z_top, length, width):
        """Closed obround through the floor/web along x: overall length x width."""
        segs = fillet_outline(rect(x - length / 2, y - width / 2, x + length / 2, y + width / 2),
                              [width / 2] * 4)
        self.tools.append(prism(segs, xy_at(-1.0), (0, 0, z_top + 1.5)))
        self.corner_radii.append(width / 2)
        self.slots.append({"length": r6(length), "width": r6(width), "center": [r6(x), r6(y), r6(z_top)],
                           "direction": [1, 0, 0], "axis": [0, 0, 1], "through": True})

    def cutout(self, wall_id, axis, wall_mid, t, along, top, width, depth, shape="rect"):
        """An opening from a vertical wall's top edge down. axis: 'x' = wall normal is x
        (wall runs along y), 'y' = wall normal is y. along = centre along the wall.
        shape 'rect' = flat bottom; 'U' = semicircular bottom of radius width/2."""
        over = 1.0
        a0, a1 = along - width / 2, along + width / 2
        ztop = top + 2.0
        if shape == "rect":
            pts2 = rect(a0, top - depth, a1, ztop)
            segs = fillet_outline(pts2, [0] * 4)
        else:
            R = width / 2
            zc = top - depth + R
            segs = [("line", (a1, ztop), (a0, ztop)), ("line", (a0, ztop), (a0, zc)),
                    ("arc", (a0, zc), (along, zc - R), (a1, zc)), ("line", (a1, zc), (a1, ztop))]
            self.corner_radii.append(R)
        n0 = wall_mid - t / 2 - over
        if axis == "x":
            tool = prism(segs, lambda p: gp_Pnt(n0, p[0], p[1]), (t + 2 * over, 0, 0))
            centre = [wall_mid, along, top - depth / 2]
        else:
            tool = prism(segs, lambda p: gp_Pnt(p[0], n0, p[1]), (0, t + 2 * over, 0))
            centre = [along, wall_mid, top - depth / 2]
        self.tools.append(tool)
        c = {"wall": wall_id, "width": r6(width), "depth": r6(depth),
             "center": [r6(v) for v in centre], "from": "top", "shape": shape}
        if shape == "U":
            c["bottom_radius"] = r6(width / 2)
        self.cutouts.append(c)

    # -- result
    def labels(self, vol):
        vert = [w["height"] / w["thickness"] for w in self.walls if w["role"] != "web"]
        return {
            "name": self.name, "family": self.family, "variant": self.variant, "seed": self.seed,
            "generator": GENERATOR, "generator_version": GENERATOR_VERSION,
            "units": "mm", "up": [0, 0, 1],
            "bbox": [r6(v) for v in self.bbox], "volume": r6(vol),
            "params": self.params,
            "walls": self.walls,
            "crossings": self.crossings, "t_joints": self.t_joints,
            "holes": self.holes, "cutouts": self.cutouts, "slots": self.slots,
            "pockets": self.pockets,
            "fillets": {"vertical_corner_radius": self.vertical_R, "floor_radius": self.floor_r,
                        "adjustments": self.adjust},
            "min_corner_radius": r6(min(self.corner_radii)) if self.corner_radii else None,
            "max_wall_slenderness": r6(max(vert)) if vert else None,
        }


def perimeter_flanges(p, L, W, tf, h, extra_h=None):
    """The four perimeter walls of an L x W rectangle, thickness tf, free height h.
    Returns ids (y0, y1, x0, x1)."""
    hh = extra_h or {}
    f_y0 = p.wall("flange", tf, hh.get("y0", h), L, (0, 1, 0), tf / 2)
    f_y1 = p.wall("flange", tf, hh.get("y1", h), L, (0, 1, 0), W - tf / 2)
    f_x0 = p.wall("flange", tf, hh.get("x0", h), W, (1, 0, 0), tf / 2)
    f_x1 = p.wall("flange", tf, hh.get("x1", h), W, (1, 0, 0), L - tf / 2)
    return f_y0, f_y1, f_x0, f_x1


# --------------------------------------------------------------------------- families

def wing_rib(name, seed, idx):
    p = Part(name, "wing_rib", "stiffened_web", seed)
    g = p.rng
    L = uni(g, 200, 480, 1)
    W = uni(g, 80, 170, 1)
    tw = uni(g, 1.5, 4.0)
    tf = uni(g, 1.2, 3.0)
    h = uni(g, 15, 40, 0.5)
    ts = uni(g, 1.2, 3.0)
    R = uni(g, 3, 8, 0.5)
    floor_r = uni(g, 1, 3, 0.5) if g.random() < 0.5 else None
    ns = min(g.randint(0, 3), int((L - 2 * tf) // 60) - 1)
    H = tw + h
    p.bbox = [0, 0, 0, L, W, H]
    p.vertical_R, p.floor_r = R, floor_r
    p.params = {"length": L, "width": W, "web_thickness": tw, "flange_thickness": tf,
                "flange_height": h, "stiffener_thickness": ts, "stiffeners": ns}
    p.base = box(0, 0, 0, L, W, H)
    web = p.wall("web", tw, tw, L, (0, 0, 1), tw / 2, width=W)
    fy0, fy1, fx0, fx1 = perimeter_flanges(p, L, W, tf, h)
    # stiffener mid-planes, evenly spaced with jitter
    xs = []
    inner = L - 2 * tf
    for i in range(ns):
        base_x = tf + inner * (i + 1) / (ns + 1)
        xs.append(q(base_x + g.uniform(-0.08, 0.08) * inner / (ns + 1), 0.5))
    stiff = []
    for x in xs:
        sid = p.wall("rib", ts, h, W - 2 * tf, (1, 0, 0), x)
        stiff.append((sid, x))
        p.t_joints += [[sid, fy0], [sid, fy1]]
    # bays
    edges = [tf] + [v for x in xs for v in (x - ts / 2, x + ts / 2)] + [L - tf]
    bays = [(edges[2 * i], edges[2 * i + 1]) for i in range(ns + 1)]
    spare = None
    for (a, b) in bays:
        poly = rect(a, tf, b, W - tf)
        R_used, fr = p.pocket(poly, R, tw, H + 1, floor_r, h, floor_wall=web)
        # lightening hole in the bay
        room = min(b - a, W - 2 * tf) - 2 * ((fr or 0) + 4)
        d = q(min(g.uniform(20, 60), room), 0.5)
        if room >= 20 and g.random() < 0.85:
            p.hole(q((a + b) / 2, 0.1), W / 2, tw, d)
        elif room >= 20 and spare is None:
            spare = (q((a + b) / 2, 0.1), d)
    if not p.holes and spare:  # every rib gets at least one lightening hole
        p.hole(spare[0], W / 2, tw, spare[1])
    # U-shaped cut-outs (mouse-hole style) from the top edge of stiffeners, or of a
    # long flange when there is no stiffener
    targets = [(sid, "x", x, ts, W - 2 * tf, tf) for (sid, x) in stiff]
    if not targets:
        targets = [(fy0, "y", tf / 2, tf, L - 2 * tf, tf)]
    for (wid, axis, mid, t, span, start) in targets:
        if g.random() < 0.6:
            Rn = uni(g, 5, 12, 0.5)
            dmax = h - (floor_r or 0) - 3
            if dmax < Rn:
                continue
            depth = q(min(Rn + g.uniform(0, 12), dmax), 0.5)
            margin = Rn + R + 3
            if span < 2 * margin:
                continue
            along = q(start + span / 2 + g.uniform(-0.25, 0.25) * (span - 2 * margin), 0.5)
            p.cutout(wid, axis, mid, t, along, H, 2 * Rn, depth, shape="U")
    return p


def grid_panel(name, seed, idx, iso):
    p = Part(name, "grid_panel", "isogrid" if iso else "orthogrid", seed)
    g = p.rng
    tw = uni(g, 2.0, 4.0)
    t = uni(g, 1.2, 3.0)
    h = uni(g, 10, 30, 0.5)
    tf = q(max(t, uni(g, 1.5, 4.0)))
    R = uni(g, 3, 8, 0.5)
    floor_r = uni(g, 1, 3, 0.5) if g.random() < 0.5 else None
    H = tw + h
    if not iso:
        nx, ny = g.randint(2, 5), g.randint(2, 4)
        px, py = uni(g, 40, 80, 1), uni(g, 40, 80, 1)
        L, W = q(nx * px + 2 * tf), q(ny * py + 2 * tf)
    else:
        s = uni(g, 55, 90, 1)  # triangle side (node pitch along x)
        hr = s * SQ3 / 2
        n_rows = g.choice([2, 4])
        m = g.randint(3, 5) if n_rows == 4 else g.randint(3, 6)
        L, W = m * s + 2 * tf, n_rows * hr + 2 * tf
    p.bbox = [0, 0, 0, L, W, H]
    p.vertical_R, p.floor_r = R, floor_r
    p.base = box(0, 0, 0, L, W, H)
    web = p.wall("web", tw, tw, L, (0, 0, 1), tw / 2, width=W)
    fy0, fy1, fx0, fx1 = perimeter_flanges(p, L, W, tf, h)
    x0, y0, x1, y1 = tf, tf, L - tf, W - tf
    frame_hp = [(-1, 0, -x0), (1, 0, x1), (0, -1, -y0), (0, 1, y1)]
    if not iso:
        p.params = {"length": L, "width": W, "floor_thickness": tw, "frame_thickness": tf,
                    "rib_thickness": t, "rib_height": h, "cells": [nx, ny], "pitch": [px, py]}
        xr = [tf + i * px for i in range(1, nx)]
        yr = [tf + j * py for j in range(1, ny)]
        xid = [p.wall("rib", t, h, W - 2 * tf, (1, 0, 0), x) for x in xr]
        yid = [p.wall("rib", t, h, L - 2 * tf, (0, 1, 0), y) for y in yr]
        for a in xid:
            p.t_joints += [[a, fy0], [a, fy1]]
        for b in yid:
            p.t_joints += [[b, fx0], [b, fx1]]
        p.crossings = [[a, b] for a in xid for b in yid]
        xe = [x0] + xr + [x1]
        ye = [y0] + yr + [y1]
        for j in range(ny):
            for i in range(nx):
                xa = xe[i] + (t / 2 if i > 0 else 0)
                xb = xe[i + 1] - (t / 2 if i + 1 < nx else 0)
                ya = ye[j] + (t / 2 if j > 0 else 0)
                yb = ye[j + 1] - (t / 2 if j + 1 < ny else 0)
                p.pocket(rect(xa, ya, xb, yb), R, tw, H + 1, floor_r, h, floor_wall=web)
        return p
    # isogrid: horizontal ribs at rows 1..n-1, and lines at 60/120 deg through the nodes.
    p.params = {"length": r6(L), "width": r6(W), "floor_thickness": tw, "frame_thickness": tf,
                "rib_thickness": t, "rib_height": h, "node_pitch": s, "rows": n_rows,
                "columns": m}
    lines = []  # (normal, offset, kind)
    for k in range(1, n_rows):
        lines.append(((0.0, 1.0), y0 + k * hr, "row", k))
    # 60 deg: x - (y-y0)/sqrt3 = x0 + s/2 + i*s ; 120 deg: x + (y-y0)/sqrt3 = x0 + s/2 + j*s
    n60 = (SQ3 / 2, -0.5)
    n120 = (SQ3 / 2, 0.5)
    Hi = y1 - y0
    for fam, nn, sgn in (("d60", n60, -1), ("d120", n120, 1)):
        lo = math.floor((-Hi / SQ3 - s) / s) - 1
        hi = math.ceil((x1 - x0) / s) + 1
        for i in range(lo, hi + 1):
            c = x0 + s / 2 + i * s  # value of x + sgn*(y-y0)/sqrt3 on the line
            # n.x = (sqrt3/2)*(x + sgn*y/sqrt3) = (sqrt3/2)*(c + sgn*y0/sqrt3)
            d = (SQ3 / 2) * (c + sgn * y0 / SQ3)
            lines.append((nn, d, fam, i))

    def clip_line(nn, d):
        # points of the line n.x = d inside [x0,x1]x[y0,y1]
        dirv = (-nn[1], nn[0])
        p0 = (nn[0] * d, nn[1] * d)
        tmin, tmax = -1e9, 1e9
        for (a, lo_, hi_) in ((0, x0, x1), (1, y0, y1)):
            if abs(dirv[a]) < 1e-12:
                if not (lo_ - 1e-9 <= p0[a] <= hi_ + 1e-9):
                    return None
                continue
            ta, tb = (lo_ - p0[a]) / dirv[a], (hi_ - p0[a]) / dirv[a]
            tmin, tmax = max(tmin, min(ta, tb)), min(tmax, max(ta, tb))
        if tmax - tmin < 1e-6:
            return None
        return (p0[0] + tmin * dirv[0], p0[1] + tmin * dirv[1]), (p0[0] + tmax * dirv[0], p0[1] + tmax * dirv[1])

    ribs = []  # (id, nn, d, seg)
    for (nn, d, fam, i) in lines:
        seg = clip_line(nn, d)
        if seg is None:
            continue
        wid = p.wall("rib", t, h, math.dist(*seg), (nn[0], nn[1], 0), d)
        ribs.append((wid, nn, d, seg, fam))
        for end in seg:
            for (fid, on) in ((fx0, abs(end[0] - x0) < 1e-6), (fx1, abs(end[0] - x1) < 1e-6),
                              (fy0, abs(end[1] - y0) < 1e-6), (fy1, abs(end[1] - y1) < 1e-6)):
                if on and [wid, fid] not in p.t_joints:
                    p.t_joints.append([wid, fid])
    for a in range(len(ribs)):
        for b in range(a + 1, len(ribs)):
            (ia, na, da, _, fa), (ib, nb, db, _, fb) = ribs[a], ribs[b]
            if fa == fb:
                continue
            det = na[0] * nb[1] - na[1] * nb[0]
            x = (da * nb[1] - db * na[1]) / det
            y = (na[0] * db - nb[0] * da) / det
            if x0 + t < x < x1 - t and y0 + t < y < y1 - t:
                p.crossings.append([ia, ib])
    # cells: per row strip, pieces between consecutive diagonals
    for k in range(n_rows):
        ya, yb = y0 + k * hr, y0 + (k + 1) * hr
        ym = (ya + yb) / 2
        diag = []
        for (wid, nn, d, seg, fam) in ribs:
            if fam == "row":
                continue
            xm = (d - nn[1] * ym) / nn[0]
            if x0 - 1e-6 < xm < x1 + 1e-6:
                diag.append((xm, nn, d))
        diag.sort()
        bounds = [(x0, None, None)] + diag + [(x1, None, None)]
        for j in range(len(bounds) - 1):
            (xa, na_, da_), (xb, nb_, db_) = bounds[j], bounds[j + 1]
            if xb - xa < 1e-6:
                continue
            tp = ((xa + xb) / 2, ym)
            hps = list(frame_hp)
            hps.append((0, -1, -(ya + (t / 2 if k > 0 else 0))))
            hps.append((0, 1, yb - (t / 2 if k + 1 < n_rows else 0)))
            for (nn, d) in ((na_, da_), (nb_, db_)):
                if nn is None:
                    continue
                if nn[0] * tp[0] + nn[1] * tp[1] < d:
                    hps.append((nn[0], nn[1], d - t / 2))
                else:
                    hps.append((-nn[0], -nn[1], -d - t / 2))
            poly = clip_halfplanes(hps)
            if not poly or poly_area(poly) < 1.0:
                raise PartError("degenerate isogrid cell")
            p.pocket(poly, R, tw, H + 1, floor_r, h, floor_wall=web)
    return p


def egg_crate(name, seed, idx):
    p = Part(name, "egg_crate", "crossing_ribs", seed)
    g = p.rng
    tw = uni(g, 1.5, 3.0)
    t = uni(g, 1.0, 2.0)
    h = min(uni(g, 30, 60, 0.5), q(50 * t, 0.5))
    R = uni(g, 4, 8, 0.5)
    floor_r = uni(g, 1, 2, 0.5) if g.random() < 0.4 else None
    nx, ny = g.randint(2, 5), g.randint(2, 4)
    px, py = uni(g, 40, 70, 1), uni(g, 40, 70, 1)
    ex, ey = uni(g, 0.5 * px, 0.8 * px, 1), uni(g, 0.5 * py, 0.8 * py, 1)
    L = q(2 * ex + (nx - 1) * px)
    W = q(2 * ey + (ny - 1) * py)
    H = tw + h
    p.bbox = [0, 0, 0, L, W, H]
    p.vertical_R, p.floor_r = R, floor_r
    p.params = {"length": L, "width": W, "floor_thickness": tw, "rib_thickness": t,
                "rib_height": h, "ribs": [nx, ny], "pitch": [px, py], "edge_margin": [ex, ey]}
    p.base = box(0, 0, 0, L, W, H)
    web = p.wall("web", tw, tw, L, (0, 0, 1), tw / 2, width=W)
    xr = [q(ex + i * px) for i in range(nx)]
    yr = [q(ey + j * py) for j in range(ny)]
    xid = [p.wall("rib", t, h, W, (1, 0, 0), x) for x in xr]
    yid = [p.wall("rib", t, h, L, (0, 1, 0), y) for y in yr]
    p.crossings = [[a, b] for a in xid for b in yid]
    E = R + 3  # open cells' tools run past the floor edge
    xe = [-E] + xr + [L + E]
    ye = [-E] + yr + [W + E]
    for j in range(ny + 1):
        for i in range(nx + 1):
            xa = xe[i] + (t / 2 if i > 0 else 0)
            xb = xe[i + 1] - (t / 2 if i < nx else 0)
            ya = ye[j] + (t / 2 if j > 0 else 0)
            yb = ye[j + 1] - (t / 2 if j < ny else 0)
            closed = 0 < i < nx and 0 < j < ny
            extra = None
            if not closed:
                open_sides = [s for s, c in (("-x", i == 0), ("+x", i == nx), ("-y", j == 0),
                                             ("+y", j == ny)) if c]
                extra = {"open_sides": open_sides}
            poly = rect(xa, ya, xb, yb)
            p.pocket(poly, R, tw, H + 1, floor_r, h, closed=closed, floor_wall=web, extra=extra)
            if not closed:  # the label's outline: clipped to the part
                p.pockets[-1]["polygon"] = [[r6(min(max(x, 0), L)), r6(min(max(y, 0), W))]
                                            for (x, y) in poly]
    return p


def flange_web(name, seed, idx):
    variant = ["L", "T", "U"][idx % 3]
    p = Part(name, "flange_web", variant, seed)
    g = p.rng
    L = uni(g, 120, 300, 1)
    W = uni(g, 50, 120, 1)
    tw = uni(g, 1.5, 4.0)
    tf = uni(g, 1.2, 3.0)
    h = uni(g, 15, 40, 0.5)
    floor_r = uni(g, 1, 3, 0.5) if g.random() < 0.5 else None
    H = tw + h
    p.bbox = [0, 0, 0, L, W, H]
    p.floor_r = floor_r
    p.params = {"length": L, "width": W, "web_thickness": tw, "flange_thickness": tf,
                "flange_height": h}
    fr = floor_r or 0
    # cross-section in the YZ plane (u = y, v = z), extruded along +X
    if variant == "L":
        prof = [(0, 0), (W, 0), (W, tw), (tf, tw), (tf, H), (0, H)]
        rad = [0, 0, 0, fr, 0, 0]
        verticals = [("flange", tf / 2)]
        free = [(tf + fr + 4, W - 4)]
    elif variant == "U":
        prof = [(0, 0), (W, 0), (W, H), (W - tf, H), (W - tf, tw), (tf, tw), (tf, H), (0, H)]
        rad = [0, 0, 0, 0, fr, fr, 0, 0]
        verticals = [("flange", tf / 2), ("flange", W - tf / 2)]
        free = [(tf + fr + 4, W - tf - fr - 4)]
    else:  # inverted T: a central upstand on the web
        yc = q(W / 2, 0.1)
        a, b = yc - tf / 2, yc + tf / 2
        prof = [(0, 0), (W, 0), (W, tw), (b, tw), (b, H), (a, H), (a, tw), (0, tw)]
        rad = [0, 0, 0, fr, 0, 0, fr, 0]
        verticals = [("rib", yc)]
        free = [(4, a - fr - 4), (b + fr + 4, W - 4)]
    segs = fillet_outline(prof, rad)
    if segs is None:
        raise PartError("profile")
    p.base = prism(segs, lambda pt: gp_Pnt(0, pt[0], pt[1]), (L, 0, 0))
    web = p.wall("web", tw, tw, L, (0, 0, 1), tw / 2, width=W)
    vids = [(p.wall(role, tf, h, L, (0, 1, 0), y), y) for (role, y) in verticals]
    # cut-outs from the top edge of the vertical walls
    for (wid, y) in vids:
        n = g.choice([1, 1, 2])
        xs = [L * (k + 1) / (n + 1) for k in range(n)]
        for x in xs:
            w = uni(g, 15, 40, 0.5)
            d = min(uni(g, 8, 20, 0.5), q(h - fr - 3, 0.5))
            x = q(x + g.uniform(-0.1, 0.1) * L / (n + 1), 0.5)
            p.cutout(wid, "y", y, tf, x, H, w, d, shape="rect")
    # slots and holes through the web, in the free strips
    strips = [s for s in free if s[1] - s[0] >= 8]
    n_feat = 0
    for (ya, yb) in strips:
        room = yb - ya
        if g.random() < 0.7 and room >= 8:
            wdt = min(uni(g, 6, 16, 0.5), q(room - 1, 0.5))
            ln = uni(g, max(20, 2 * wdt + 4), 60, 0.5)
            x = q(L * g.uniform(0.3, 0.7), 0.5)
            p.slot(x, q((ya + yb) / 2, 0.1), tw, ln, wdt)
            n_feat += 1
            xs_taken = (x - ln / 2, x + ln / 2)
        else:
            xs_taken = None
        nh = g.randint(1, 3) if n_feat == 0 or g.random() < 0.6 else 0
        for k in range(nh):
            d = min(uni(g, 6, 20, 0.5), q(room - 1, 0.5))
            x = q(L * (k + 1) / (nh + 1), 0.5)
            if d < 3 or (xs_taken and xs_taken[0] - d < x < xs_taken[1] + d):
                continue
            p.hole(x, q((ya + yb) / 2, 0.1), tw, d)
            n_feat += 1
    if not p.holes and not p.slots and strips:
        ya, yb = strips[0]
        d = min(10.0, q(yb - ya - 1, 0.5))
        p.hole(q(L * 0.15, 0.5), q((ya + yb) / 2, 0.1), tw, d)
    return p


def pocket_frame(name, seed, idx):
    p = Part(name, "pocket_frame", "multi_depth", seed)
    g = p.rng
    L = uni(g, 120, 250, 1)
    W = uni(g, 80, 160, 1)
    H = uni(g, 20, 40, 0.5)
    to = uni(g, 2.0, 4.0)
    ti = uni(g, 1.5, 4.0)
    R = uni(g, 4, 10, 0.5)
    layouts = [(2, 1), (3, 1), (2, 2), (3, 2), (4, 1), (1, 2)]
    nx, ny = layouts[idx % len(layouts)]
    p.bbox = [0, 0, 0, L, W, H]
    p.vertical_R = R
    p.base = box(0, 0, 0, L, W, H)
    # cell boundaries with random proportions
    def split(total, n, t_out, t_in):
        free = total - 2 * t_out - (n - 1) * t_in
        w = [g.uniform(0.7, 1.3) for _ in range(n)]
        s = sum(w)
        sizes = [q(free * v / s, 0.5) for v in w]
        sizes[-1] = q(free - sum(sizes[:-1]), 0.001)
        edges, x = [], t_out
        for k in range(n):
            edges.append((x, x + sizes[k]))
            x += sizes[k] + t_in
        return edges
    cx, cy = split(L, nx, to, ti), split(W, ny, to, ti)
    ncell = nx * ny
    # distinct depths, floors >= 1.5
    dmax, dmin = H - 1.5, max(6.0, 0.3 * H)
    depths = []
    while len(depths) < ncell:
        d = uni(g, dmin, dmax, 0.5)
        if all(abs(d - e) >= 1.0 for e in depths):
            depths.append(d)
    floor_r_any = []
    p.params = {"length": L, "width": W, "height": H, "outer_wall": to, "inner_wall": ti,
                "cells": [nx, ny]}
    # webs (pocket floors) first, then perimeter, then inner walls
    cells = {}
    for j in range(ny):
        for i in range(nx):
            d = depths[j * nx + i]
            (xa, xb), (ya, yb) = cx[i], cy[j]
            fid = p.wall("web", H - d, H - d, xb - xa, (0, 0, 1), (H - d) / 2, width=yb - ya)
            cells[(i, j)] = (d, fid)
    def dep(i, j):
        return cells[(i, j)][0]
    hy0 = max(dep(i, 0) for i in range(nx))
    hy1 = max(dep(i, ny - 1) for i in range(nx))
    hx0 = max(dep(0, j) for j in range(ny))
    hx1 = max(dep(nx - 1, j) for j in range(ny))
    fy0, fy1, fx0, fx1 = perimeter_flanges(p, L, W, to, None,
                                           {"y0": hy0, "y1": hy1, "x0": hx0, "x1": hx1})
    xw = []
    for i in range(1, nx):
        x = cx[i][0] - ti / 2
        segs = [(min(dep(i - 1, j), dep(i, j)), max(dep(i - 1, j), dep(i, j))) for j in range(ny)]
        wid = p.wall("rib", ti, max(a for a, _ in segs), W - 2 * to, (1, 0, 0), x,
                     height_max=r6(max(b for _, b in segs)))
        xw.append(wid)
        p.t_joints += [[wid, fy0], [wid, fy1]]
    yw = []
    for j in range(1, ny):
        y = cy[j][0] - ti / 2
        segs = [(min(dep(i, j - 1), dep(i, j)), max(dep(i, j - 1), dep(i, j))) for i in range(nx)]
        wid = p.wall("rib", ti, max(a for a, _ in segs), L - 2 * to, (0, 1, 0), y,
                     height_max=r6(max(b for _, b in segs)))
        yw.append(wid)
        p.t_joints += [[wid, fx0], [wid, fx1]]
    p.crossings = [[a, b] for a in xw for b in yw]
    through_cell = g.randrange(ncell) if g.random() < 0.6 else None
    for j in range(ny):
        for i in range(nx):
            d, fid = cells[(i, j)]
            (xa, xb), (ya, yb) = cx[i], cy[j]
            fr = uni(g, 1.0, 2.0, 0.5) if g.random() < 0.4 else None
            if fr:
                floor_r_any.append(fr)
            _, fr_used = p.pocket(rect(xa, ya, xb, yb), R, H - d, H + 1, fr, d, floor_wall=fid)
            if through_cell == j * nx + i:
                room = min(xb - xa, yb - ya) - 2 * ((fr_used or 0) + R + 2)
                if room >= 8:
                    zf = H - d
                    if g.random() < 0.5:
                        dd = q(min(g.uniform(10, 30), room), 0.5)
                        p.hole(q((xa + xb) / 2, 0.1), q((ya + yb) / 2, 0.1), zf, dd)
                    else:
                        wdt = q(min(g.uniform(8, 14), room), 0.5)
                        ln = q(min(g.uniform(wdt + 6, 50), (xb - xa) - 2 * ((fr_used or 0) + R + 2)), 0.5)
                        if ln > wdt:
                            p.slot(q((xa + xb) / 2, 0.1), q((ya + yb) / 2, 0.1), zf, ln, wdt)
    p.floor_r = max(floor_r_any) if floor_r_any else None
    p.params["pocket_depths"] = depths
    return p


def catalogue():
    """(name, builder) for every part, in order."""
    out = []
    for i in range(11):
        out.append((f"wing_rib_{i + 1:02d}", lambda n, s, i=i: wing_rib(n, s, i)))
    for i in range(6):
        out.append((f"orthogrid_{i + 1:02d}", lambda n, s, i=i: grid_panel(n, s, i, False)))
    for i in range(5):
        out.append((f"isogrid_{i + 1:02d}", lambda n, s, i=i: grid_panel(n, s, i, True)))
    for i in range(9):
        out.append((f"egg_crate_{i + 1:02d}", lambda n, s, i=i: egg_crate(n, s, i)))
    for i in range(9):
        out.append((f"flange_web_{i + 1:02d}", lambda n, s, i=i: flange_web(n, s, i)))
    for i in range(9):
        out.append((f"pocket_frame_{i + 1:02d}", lambda n, s, i=i: pocket_frame(n, s, i)))
    return out


# --------------------------------------------------------------------------- driver

def build(name, builder, seed):
    p = builder(name, seed)
    solid = cut_all(p.base, p.tools)
    return p, solid


def check_written(out, name, labels):
    """Re-read the STEP with OCC: one valid closed solid, volume and bbox as labelled."""
    problems = []
    shape = read_step(os.path.join(out, name + ".step"))
    try:
        solid = single_solid(shape)
    except PartError as e:
        return [str(e)]
    if not is_valid(solid):
        problems.append("BRepCheck: invalid")
    if not shells_closed(solid):
        problems.append("shell not closed")
    v = volume(solid)
    if abs(v - labels["volume"]) > 1e-6 * abs(labels["volume"]):
        problems.append(f"volume {v} != {labels['volume']}")
    bb = occ_bbox(solid)
    if max(abs(a - b) for a, b in zip(bb, labels["bbox"])) > 1e-4:
        problems.append(f"bbox {bb} != {labels['bbox']}")
    return problems


def dump(obj):
    return json.dumps(obj, indent=1) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="output directory")
    ap.add_argument("--seed", type=int, default=DEFAULT_SEED)
    ap.add_argument("--only", default=None, help="comma-separated part names")
    ap.add_argument("--check", action="store_true", help="re-read every STEP written and verify it")
    ap.add_argument("--list", action="store_true", help="print the part names and exit")
    a = ap.parse_args(argv)
    cat = catalogue()
    if a.list:
        print("\n".join(n for n, _ in cat))
        return 0
    if a.only:
        want = set(a.only.split(","))
        unknown = want - {n for n, _ in cat}
        if unknown:
            sys.exit(f"unknown part(s): {', '.join(sorted(unknown))}")
        cat = [(n, b) for n, b in cat if n in want]
    os.makedirs(a.out, exist_ok=True)
    t_all = time.time()
    index, failures = [], []
    for name, builder in cat:
        t0 = time.time()
        try:
            p, solid = build(name, builder, a.seed)
            vol = volume(solid)
            labels = p.labels(vol)
            write_step(solid, os.path.join(a.out, name + ".step"), name)
            with open(os.path.join(a.out, name + ".labels.json"), "w") as fh:
                fh.write(dump(labels))
        except PartError as e:
            failures.append(name)
            print(f"FAILED {name}: {e}", file=sys.stderr)
            continue
        msg = ""
        if a.check:
            probs = check_written(a.out, name, labels)
            if probs:
                failures.append(name)
                msg = "  CHECK FAILED: " + "; ".join(probs)
            else:
                msg = "  check ok"
        adj = f"  adjusted: {labels['fillets']['adjustments']}" if labels["fillets"]["adjustments"] else ""
        print(f"{name:18s} {time.time() - t0:5.2f}s  vol={vol:12.1f}{msg}{adj}", file=sys.stderr)
        index.append({"name": name, "family": p.family, "variant": p.variant,
                      "bbox": labels["bbox"], "volume": labels["volume"],
                      "step": name + ".step", "labels": name + ".labels.json"})
    if not a.only:
        fam = {}
        for e in index:
            fam[e["family"]] = fam.get(e["family"], 0) + 1
        with open(os.path.join(a.out, "index.json"), "w") as fh:
            fh.write(dump({"generator": GENERATOR, "generator_version": GENERATOR_VERSION,
                           "seed": a.seed, "units": "mm", "count": len(index), "families": fam,
                           "parts": index}))
    print(f"{len(index)} parts in {time.time() - t_all:.1f}s, {len(failures)} failed"
          + (f": {', '.join(failures)}" if failures else ""), file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
