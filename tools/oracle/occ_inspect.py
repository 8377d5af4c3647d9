#!/usr/bin/env python3
"""OpenCASCADE (OCP) oracle for thinplan's STEP reader.

Reads STEP files with OCC's own STEPControl_Reader and reports, per file,
numbers our Rust reader can be checked against: solid/face counts, faces by
surface kind, optimal bounding box, volume, area, declared length unit and,
optionally, read+transfer wall time.

Usage:
    occ_inspect.py FILE_OR_DIR... [--out JSON] [--time N] [--faces-out JSON]

Directories are expanded to their *.step / *.stp files (non-recursive).
--faces-out writes, for every input file, the faces in the order
TopExp_Explorer(shape, TopAbs_FACE) visits them (index, kind, area, centroid).

All lengths are in millimetres: OCC scales what it reads to the
"xstep.cascade.unit" parameter, which we set explicitly to MM below.
"""

import argparse
import json
import os
import re
import statistics
import sys
import time

import OCP
from OCP.Bnd import Bnd_Box
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepGProp import BRepGProp
from OCP.GeomAbs import (
    GeomAbs_BezierSurface,
    GeomAbs_BSplineSurface,
    GeomAbs_Cone,
    GeomAbs_Cylinder,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_Torus,
)
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_FACE, TopAbs_SOLID
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS

# OCP 8 exposes OCC's collection typedefs (TopTools_IndexedMapOfShape,
# TColStd_SequenceOfAsciiString) as template instantiations in OCP.OCP.collections;
# older OCP (7.x) had them under their typedef names.
try:
    from OCP.TopTools import TopTools_IndexedMapOfShape
except ImportError:
    from OCP.OCP.collections import (
        IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as TopTools_IndexedMapOfShape)
try:
    from OCP.TColStd import TColStd_SequenceOfAsciiString
except ImportError:
    from OCP.OCP.collections import (
        Sequence_TCollection_AsciiString as TColStd_SequenceOfAsciiString)

# OCC 8 made TopoDS a namespace (TopoDS.Face); OCP 7.x bound it as TopoDS.Face_s.
_to_face = getattr(TopoDS, "Face_s", None) or TopoDS.Face

KINDS = ("plane", "cylinder", "cone", "sphere", "torus", "bspline", "other")
_KIND_OF = {
    GeomAbs_Plane: "plane",
    GeomAbs_Cylinder: "cylinder",
    GeomAbs_Cone: "cone",
    GeomAbs_Sphere: "sphere",
    GeomAbs_Torus: "torus",
    GeomAbs_BSplineSurface: "bspline",
    GeomAbs_BezierSurface: "bspline",  # Bezier is a special B-spline
}


def occ_version():
    # OCP's version is OCC's version plus one packaging digit (8.0.1.1 -> OCC 8.0.1).
    v = getattr(OCP, "__version__", "unknown")
    parts = v.split(".")
    return ".".join(parts[:3]) if len(parts) >= 3 else v


def _set_mm():
    # Make sure OCC converts whatever the file declares into millimetres.
    Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")


# ---------------------------------------------------------------------------
# Declared unit: a plain text scan of the STEP file, not a real parse. It looks
# for the length-unit entity forms that CAD exporters write:
#   SI_UNIT(.MILLI.,.METRE.) -> "mm"    SI_UNIT($,.METRE.) -> "m"
#   SI_UNIT(.CENTI.,.METRE.) -> "cm"    SI_UNIT(.MICRO.,.METRE.) -> "um"
#   CONVERSION_BASED_UNIT('INCH',...) -> "inch"  ('FOOT' -> "ft")
# A conversion-based unit is defined through an SI base unit
# (LENGTH_MEASURE_WITH_UNIT(25.4, <mm>)), so when one is present the SI hits are
# taken as its base and the conversion-based name wins. Several distinct units
# otherwise (e.g. an assembly mixing units) give "mixed:<a>,<b>"; none gives null. OCC's own view
# (STEPControl_Reader.FileUnits) is reported beside it as "units_occ".
# ---------------------------------------------------------------------------
_SI_LEN = re.compile(r"SI_UNIT\s*\(\s*(\$|\.[A-Z]+\.)\s*,\s*\.METRE\.\s*\)")
_CONV = re.compile(r"CONVERSION_BASED_UNIT\s*\(\s*'([^']*)'")
_PREFIX = {"$": "m", ".MILLI.": "mm", ".CENTI.": "cm", ".MICRO.": "um",
           ".KILO.": "km", ".DECI.": "dm", ".NANO.": "nm"}
_CONV_NAME = {"INCH": "inch", "FOOT": "ft", "MILLIMETRE": "mm", "METRE": "m",
              "MIL": "mil", "YARD": "yd", "MILE": "mile"}


def declared_unit(text):
    conv = []
    for m in _CONV.finditer(text):
        name = m.group(1).strip().upper()
        if name in _CONV_NAME:  # skip angle conversions such as 'DEGREE'
            conv.append(_CONV_NAME[name])
    si = [_PREFIX.get(m.group(1), m.group(1)) for m in _SI_LEN.finditer(text)]
    uniq = sorted(set(conv or si))
    if not uniq:
        return None
    if len(uniq) == 1:
        return uniq[0]
    return "mixed:" + ",".join(uniq)


def read_step(path):
    """Read + transfer; returns (reader, shape). Raises on failure."""
    reader = STEPControl_Reader()
    status = reader.ReadFile(path)
    if status != IFSelect_RetDone:
        raise RuntimeError(f"ReadFile failed with status {status}")
    reader.TransferRoots()
    shape = reader.OneShape()
    if shape.IsNull():
        raise RuntimeError("transfer produced a null shape")
    return reader, shape


def surface_kind(face):
    return _KIND_OF.get(BRepAdaptor_Surface(face).GetType(), "other")


def face_props(face):
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    c = props.CentreOfMass()
    return props.Mass(), [c.X(), c.Y(), c.Z()]


def explorer_faces(shape):
    """Faces in TopExp_Explorer order (repeats included)."""
    out = []
    exp = TopExp_Explorer(shape, TopAbs_FACE)
    i = 0
    while exp.More():
        face = _to_face(exp.Current())
        area, centroid = face_props(face)
        out.append({"index": i, "kind": surface_kind(face),
                    "area": area, "centroid": centroid})
        i += 1
        exp.Next()
    return out


def count(shape, kind):
    n = 0
    exp = TopExp_Explorer(shape, kind)
    while exp.More():
        n += 1
        exp.Next()
    return n


def inspect(path, time_runs=0):
    with open(path, "r", errors="replace") as fh:
        text = fh.read()
    res = {"units": declared_unit(text), "file_bytes": os.path.getsize(path)}

    reader, shape = read_step(path)

    lens, angs, solids_ = (TColStd_SequenceOfAsciiString() for _ in range(3))
    try:
        reader.FileUnits(lens, angs, solids_)
        occ_units = sorted({lens.Value(i).ToCString() for i in range(1, lens.Length() + 1)})
        res["units_occ"] = occ_units
    except Exception as e:  # pragma: no cover - informative only
        res["units_occ"] = f"error: {e}"

    res["solids"] = count(shape, TopAbs_SOLID)
    res["faces"] = count(shape, TopAbs_FACE)

    fmap = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, fmap)
    res["unique_faces"] = fmap.Extent()
    by_kind = {k: 0 for k in KINDS}
    for i in range(1, fmap.Extent() + 1):
        by_kind[surface_kind(_to_face(fmap.FindKey(i)))] += 1
    res["faces_by_kind"] = by_kind

    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(shape, box, False, False)
    # Bnd_Box.Get() returns a struct OCP 8 cannot convert; use the corners.
    lo, hi = box.CornerMin(), box.CornerMax()
    xmin, ymin, zmin = lo.X(), lo.Y(), lo.Z()
    xmax, ymax, zmax = hi.X(), hi.Y(), hi.Z()
    res["bbox_min"] = [xmin, ymin, zmin]
    res["bbox_max"] = [xmax, ymax, zmax]
    res["bbox"] = [xmax - xmin, ymax - ymin, zmax - zmin]

    vp = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, vp)
    res["volume"] = vp.Mass()
    sp = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape, sp)
    res["area"] = sp.Mass()

    if time_runs and time_runs > 0:
        times = []
        for _ in range(time_runs):
            t0 = time.perf_counter()
            read_step(path)
            times.append(time.perf_counter() - t0)
        res["time_s"] = statistics.median(times)
        res["time_runs"] = time_runs
    return res


def expand(args):
    files = []
    for a in args:
        if os.path.isdir(a):
            for n in sorted(os.listdir(a)):
                if n.lower().endswith((".step", ".stp")):
                    files.append(os.path.join(a, n))
        else:
            files.append(a)
    return files


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("paths", nargs="+", metavar="FILE_OR_DIR")
    ap.add_argument("--out", help="write JSON here (default: stdout)")
    ap.add_argument("--time", type=int, default=0, metavar="N",
                    help="also time read+transfer, median of N runs")
    ap.add_argument("--faces-out", metavar="JSON",
                    help="write per-face data in TopExp_Explorer order")
    a = ap.parse_args(argv)

    _set_mm()
    files = expand(a.paths)
    if not files:
        ap.error("no STEP files found")

    out = {}
    faces_out = {}
    seen = {}
    failed = 0
    for f in files:
        key = os.path.basename(f)
        if key in seen:
            sys.exit(f"duplicate basename {key}: {seen[key]} and {f}")
        seen[key] = f
        try:
            out[key] = inspect(f, a.time)
            if a.faces_out:
                _, shape = read_step(f)
                faces_out[key] = explorer_faces(shape)
        except Exception as e:
            failed += 1
            out[key] = {"error": str(e)}
            print(f"{f}: {e}", file=sys.stderr)

    meta = {"occ_version": occ_version(),
            "ocp_version": getattr(OCP, "__version__", "unknown"),
            "cascade_unit": Interface_Static.CVal_s("xstep.cascade.unit"),
            "files": len(files), "failed": failed,
            "tool": "tools/oracle/occ_inspect.py"}
    if a.time:
        ok = [v for v in out.values() if "time_s" in v]
        tot_b = sum(v["file_bytes"] for v in ok)
        tot_s = sum(v["time_s"] for v in ok)
        tot_f = sum(v["unique_faces"] for v in ok)
        meta["timing"] = {
            "runs_per_file": a.time, "files": len(ok),
            "total_bytes": tot_b, "total_mb": tot_b / 1e6,
            "total_s": tot_s,
            "mb_per_s": (tot_b / 1e6) / tot_s if tot_s else None,
            "faces": tot_f,
            "faces_per_s": tot_f / tot_s if tot_s else None,
            "cpu_count": os.cpu_count(),
        }
    out["_meta"] = meta

    def dump(obj, path):
        s = json.dumps(obj, indent=1, sort_keys=True) + "\n"
        if path:
            d = os.path.dirname(path)
            if d:
                os.makedirs(d, exist_ok=True)
            with open(path, "w") as fh:
                fh.write(s)
        else:
            sys.stdout.write(s)

    dump(out, a.out)
    if a.faces_out:
        faces_out["_meta"] = {
            "occ_version": occ_version(),
            "order": "TopExp_Explorer(shape, TopAbs_FACE), index from 0",
            "area": "BRepGProp.SurfaceProperties_s on the face (mm^2)",
            "centroid": "GProp_GProps.CentreOfMass of that (mm)"}
        dump(faces_out, a.faces_out)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
