#!/usr/bin/env python3
"""Distances from points of a tessellation to the exact faces of a STEP model, by OpenCASCADE
(cadquery-ocp): the mesh → surface half of the Hausdorff check of flatcut's STEP tessellation
(crates/step/tests/occt.rs runs it).

    python3 tools/step/check_mesh.py MODEL.step PROBES.json

PROBES.json: {"faces": [{"centroid": [x, y, z], "points": [[x, y, z], ...]}, ...]}: for each
tessellated face its centre of area (to find the OCCT face) and the points to measure. Prints
{"worst_mm": d, "faces": [d0, d1, ...]}: the largest distance from a face's points to that face's
surface (ShapeAnalysis_Surface::ValueOfUV, the global closest point).
"""

import json
import sys

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap
from OCP.ShapeAnalysis import ShapeAnalysis_Surface
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS
from OCP.gp import gp_Pnt


def main():
    step, probes = sys.argv[1], json.load(open(sys.argv[2]))
    r = STEPControl_Reader()
    if r.ReadFile(step) != IFSelect_RetDone:
        raise SystemExit(f"OpenCASCADE cannot read {step}")
    r.TransferRoots()
    m = ShapeMap()
    TopExp.MapShapes_s(r.OneShape(), TopAbs_FACE, m)
    faces = [TopoDS.Face(m.FindKey(i)) for i in range(1, m.Extent() + 1)]
    centres = []
    for f in faces:
        p = GProp_GProps()
        BRepGProp.SurfaceProperties_s(f, p)
        c = p.CentreOfMass()
        centres.append([c.X(), c.Y(), c.Z()])
    centres = np.array(centres)
    out = []
    for face in probes["faces"]:
        k = int(np.argmin(np.linalg.norm(centres - face["centroid"], axis=1)))
        sas = ShapeAnalysis_Surface(BRep_Tool.Surface_s(faces[k]))
        worst = 0.0
        for q in face["points"]:
            sas.ValueOfUV(gp_Pnt(*q), 1e-9)
            worst = max(worst, sas.Gap())
        out.append(worst)
    print(json.dumps({"worst_mm": max(out) if out else 0.0, "faces": out}))


if __name__ == "__main__":
    main()
