#!/usr/bin/env python3
"""Writes the length of every edge of a STEP model as OpenCASCADE measures it, the reference for
the lengths of the mating seams flatcut makes along the edges a model's faces share.

    python3 tools/step/edge_lengths.py MODEL.step > MODEL.edges.json

The JSON lists, per edge (in OCCT's order), its length (BRepGProp's linear properties: the
integral of the exact curve's speed), its two end points and its midpoint by arc length
(GCPnts_AbscissaPoint), so a reader can match the edges by position.
"""

import json
import sys

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepGProp import BRepGProp
from OCP.GCPnts import GCPnts_AbscissaPoint
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS


def point(p):
    return [round(p.X(), 7), round(p.Y(), 7), round(p.Z(), 7)]


def main():
    reader = STEPControl_Reader()
    if reader.ReadFile(sys.argv[1]) != IFSelect_RetDone:
        sys.exit(f"{sys.argv[1]}: not read")
    reader.TransferRoots()
    shape = reader.OneShape()
    m = ShapeMap()
    TopExp.MapShapes_s(shape, TopAbs_EDGE, m)
    edges = []
    for i in range(1, m.Extent() + 1):
        e = TopoDS.Edge(m.FindKey(i))
        if BRep_Tool.Degenerated_s(e):
            continue
        props = GProp_GProps()
        BRepGProp.LinearProperties_s(e, props)
        c = BRepAdaptor_Curve(e)
        length = props.Mass()
        mid = GCPnts_AbscissaPoint(c, 0.5 * length, c.FirstParameter()).Parameter()
        edges.append({
            "length_mm": length,
            "start": point(c.Value(c.FirstParameter())),
            "end": point(c.Value(c.LastParameter())),
            "mid": point(c.Value(mid)),
        })
    json.dump({"model": sys.argv[1].rsplit("/", 1)[-1], "edges": edges}, sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
