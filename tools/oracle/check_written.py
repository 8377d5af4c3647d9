#!/usr/bin/env python3
"""OpenCASCADE check of STEP files thinplan wrote (`write_step`).

Reads every *.step in DIR with OCC's STEPControl_Reader (lengths in mm) and
compares OCC's volume with the expected volumes in a JSON object
({"NAME": mm3}, keyed by file stem; the `write_samples` example writes it).

Per file it prints: OCC's solid count, unique face count (and the number of
ADVANCED_FACEs in the file), free edges (edges bounding only one face: an
open shell), whether BRepCheck_Analyzer finds the shape valid (closed shells,
consistent orientation, edges on their faces), faces OCC reoriented, OCC's
volume, the expected volume and the relative difference.

"Reoriented" catches faces whose orientation in the file is wrong: OCC's
reader heals shells (ShapeFix turns such faces around, after which the shape
is valid and the volume right), so the script compares each face's
orientation in OCC's shape (TopExp_Explorer order: solids, shells, faces as
listed) with the one the file gives it (ADVANCED_FACE same_sense, flipped in
an ORIENTED_CLOSED_SHELL(.F.)). It parses the file as `write_step` writes it
(one entity per line).

Exit status: 0 when every file reads, has at least one solid, no free edge,
is valid, has no reoriented face, and its volume is within --tol (default 1e-6) relative of the
expected one; 1 otherwise; 2 on bad arguments.

Usage:
    check_written.py DIR EXPECTED_JSON [--tol 1e-6] [--markdown]
"""

import argparse
import glob
import json
import os
import re
import sys

from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_SOLID
from OCP.TopExp import TopExp, TopExp_Explorer

try:
    from OCP.TopTools import TopTools_IndexedMapOfShape
except ImportError:  # OCP 8
    from OCP.OCP.collections import (
        IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as TopTools_IndexedMapOfShape)


def unique(shape, kind):
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, m)
    return m.Extent()


def count(shape, kind):
    n = 0
    exp = TopExp_Explorer(shape, kind)
    while exp.More():
        n += 1
        exp.Next()
    return n


def free_edges(shape):
    """Edges of the free boundary (bounding one face only)."""
    fb = ShapeAnalysis_FreeBounds(shape)
    n = 0
    for wires in (fb.GetClosedWires(), fb.GetOpenWires()):
        n += unique(wires, TopAbs_EDGE)
    return n


_ENTITY = re.compile(r"^#(\d+)=(.*);$")
_REF = re.compile(r"#(\d+)")


def file_face_senses(text):
    """The faces' orientations the file gives, in solid/shell/face order:
    True when the face's normal is its surface's (same_sense .T., not
    flipped by an ORIENTED_CLOSED_SHELL(.F.))."""
    ents = {}
    for line in text.splitlines():
        m = _ENTITY.match(line)
        if m:
            ents[int(m.group(1))] = m.group(2)

    def refs(body):
        return [int(x) for x in _REF.findall(body)]

    def shell(sid, flip):
        body = ents[sid]
        if body.startswith("ORIENTED_CLOSED_SHELL("):
            return shell(refs(body)[0], flip ^ body.endswith(".F.)"))
        out = []
        for f in refs(body):
            fb = ents[f]
            assert fb.startswith("ADVANCED_FACE("), fb
            out.append(fb.endswith(".T.)") ^ flip)
        return out

    senses = []
    rep = next(b for b in ents.values() if b.startswith("ADVANCED_BREP_SHAPE_REPRESENTATION("))
    for item in refs(rep)[:-1]:  # the last reference is the context
        body = ents[item]
        if body.startswith(("MANIFOLD_SOLID_BREP(", "BREP_WITH_VOIDS(")):
            for sh in refs(body):
                senses += shell(sh, False)
    return senses


def occ_face_senses(shape):
    out = []
    exp = TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        out.append(exp.Current().Orientation() == TopAbs_FORWARD)
        exp.Next()
    return out


def check(path):
    with open(path, "r", errors="replace") as fh:
        text = fh.read()
    file_faces = text.count("ADVANCED_FACE(")
    reader = STEPControl_Reader()
    if reader.ReadFile(path) != IFSelect_RetDone:
        raise RuntimeError("ReadFile failed")
    reader.TransferRoots()
    shape = reader.OneShape()
    if shape.IsNull():
        raise RuntimeError("transfer produced a null shape")
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    want, got = file_face_senses(text), occ_face_senses(shape)
    reoriented = sum(a != b for a, b in zip(want, got)) if len(want) == len(got) else None
    return {
        "reoriented": reoriented,
        "solids": count(shape, TopAbs_SOLID),
        "faces": unique(shape, TopAbs_FACE),
        "file_faces": file_faces,
        "free_edges": free_edges(shape),
        "valid": bool(BRepCheck_Analyzer(shape).IsValid()),
        "volume": props.Mass(),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir")
    ap.add_argument("expected")
    ap.add_argument("--tol", type=float, default=1e-6)
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = ap.parse_args()

    Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
    with open(args.expected) as fh:
        expected = json.load(fh)
    files = sorted(glob.glob(os.path.join(args.dir, "*.step")))
    if not files:
        print(f"no *.step files in {args.dir}", file=sys.stderr)
        return 2

    cols = ["file", "solids", "faces (OCC/file)", "free edges", "valid", "reoriented",
            "OCC volume mm3", "expected mm3", "rel. diff", "ok"]
    rows, failed = [], 0
    for path in files:
        stem = os.path.splitext(os.path.basename(path))[0]
        exp = expected.get(stem)
        try:
            r = check(path)
        except Exception as e:  # report and go on
            rows.append([stem, "-", "-", "-", "-", "-", f"error: {e}", "-", "-", "FAIL"])
            failed += 1
            continue
        rel = abs(r["volume"] - exp) / abs(exp) if exp else float("nan")
        ok = (exp is not None and rel <= args.tol and r["solids"] >= 1
              and r["free_edges"] == 0 and r["valid"] and r["reoriented"] == 0)
        failed += not ok
        rows.append([
            stem, str(r["solids"]), f'{r["faces"]}/{r["file_faces"]}', str(r["free_edges"]),
            "yes" if r["valid"] else "NO",
            "?" if r["reoriented"] is None else str(r["reoriented"]), f'{r["volume"]:.6f}',
            "-" if exp is None else f"{exp:.6f}", f"{rel:.1e}", "ok" if ok else "FAIL",
        ])

    if args.markdown:
        right = {1, 2, 3, 5, 6, 7, 8}
        print("| " + " | ".join(cols) + " |")
        print("| " + " | ".join("---:" if i in right else "---" for i in range(len(cols))) + " |")
        for row in rows:
            print("| " + " | ".join(row) + " |")
    else:
        widths = [max(len(c), *(len(r[i]) for r in rows)) for i, c in enumerate(cols)]
        print("  ".join(c.ljust(w) for c, w in zip(cols, widths)))
        for row in rows:
            print("  ".join(v.ljust(w) for v, w in zip(row, widths)))
    print(f"{len(rows) - failed}/{len(rows)} files ok (tolerance {args.tol:g} relative)",
          file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
