#!/usr/bin/env python3
"""Write tiny STEP fixtures that differ only in their declared length unit.

One OCC-written 25.4 x 50.8 x 10 box (coordinates as numbers in the file), whose
unit entity is then rewritten to millimetre, metre and inch. A reader that
honours units must report, in mm, the box times 1, 1000 and 25.4.

    make_unit_fixtures.py OUTDIR     # writes box_mm.step, box_m.step, box_inch.step
"""
import os
import re
import sys
import tempfile

from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

MM_UNIT = re.compile(
    r"#(\d+) = \( LENGTH_UNIT\(\) NAMED_UNIT\(\*\) SI_UNIT\(\.MILLI\.,\.METRE\.\) \);")


def main(outdir):
    os.makedirs(outdir, exist_ok=True)
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    w = STEPControl_Writer()
    w.Transfer(BRepPrimAPI_MakeBox(25.4, 50.8, 10.0).Shape(), STEPControl_AsIs)
    with tempfile.TemporaryDirectory() as td:
        tmp = os.path.join(td, "box.step")
        if w.Write(tmp) != IFSelect_RetDone:
            sys.exit("STEP write failed")
        text = open(tmp).read()
    # Fixed header timestamp so regenerated fixtures are byte-identical.
    text = re.sub(r"'\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d'", "'2000-01-01T00:00:00'", text, count=1)
    m = MM_UNIT.search(text)
    if not m:
        sys.exit("millimetre unit entity not found in OCC output")
    n = m.group(1)
    ids = [int(x) for x in re.findall(r"^#(\d+)\s*=", text, re.M)]
    a, b, c = max(ids) + 1, max(ids) + 2, max(ids) + 3
    variants = {
        "mm": m.group(0),
        "m": f"#{n} = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT($,.METRE.) );",
        "inch": (f"#{n} = ( CONVERSION_BASED_UNIT('INCH',#{a}) LENGTH_UNIT() "
                 f"NAMED_UNIT(#{b}) );\n"
                 f"#{a} = LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#{c});\n"
                 f"#{b} = DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.);\n"
                 f"#{c} = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );"),
    }
    for name, ent in variants.items():
        path = os.path.join(outdir, f"box_{name}.step")
        with open(path, "w") as fh:
            fh.write(text.replace(m.group(0), ent))
        print(path)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
