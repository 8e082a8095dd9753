#!/usr/bin/env python3
"""Writes the STEP test models of flatcut-step with OpenCASCADE (cadquery-ocp) and the reference
figures OpenCASCADE gives for them.

    python3 tools/step/make_models.py [OUT_DIR]        (default crates/step/tests/data)

For every model NAME it writes NAME.step and NAME.ref.json. The JSON holds, per face, the
surface type, the area from BRepGProp, the centre of area (to match faces independently of their
order), the bounding box, and points sampled on the face (on OCCT's surface, inside the trims,
by BRepClass_FaceClassifier): flatcut's tessellation must pass within its chordal tolerance of
each of them. The models:

- dome: a bicubic B-spline dome trimmed to a circle, with an off-centre round hole;
- cylinder: a 150 degree cylinder face cut by an inclined plane (an elliptical trim edge);
- cone: the whole lateral face of a cone frustum (a closed face with its seam edge);
- torus: a segment of a torus (partial in both directions);
- sphere_cap: a spherical cap above 20 degrees of latitude (its pole is a degenerate side);
- extrusion: a wave-shaped B-spline curve extruded along z (SURFACE_OF_LINEAR_EXTRUSION);
- revolution: a B-spline profile turned 270 degrees about z (SURFACE_OF_REVOLUTION);
- hull: a kayak hull lofted through B-spline sections, four B-spline faces sewn into a shell;
- fillet_box: a box with one filleted edge (a closed shell of planes and a cylinder);
- bracket_inch: a plate with a hole and a slot, written in inches (the file's unit is INCH).

`many_faces N OUT.step` writes the benchmark model (a plate with filleted holes) instead of the
set above: see tools/step/bench.py.
"""

import json
import math
import pathlib
import sys

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepAlgoAPI import BRepAlgoAPI_Common, BRepAlgoAPI_Cut
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import (BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace,
                                BRepBuilderAPI_MakeWire, BRepBuilderAPI_Sewing,
                                BRepBuilderAPI_Transform)
from OCP.BRepClass import BRepClass_FaceClassifier
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepGProp import BRepGProp
from OCP.BRepOffsetAPI import BRepOffsetAPI_ThruSections
from OCP.BRepPrimAPI import (BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCone,
                             BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakeHalfSpace,
                             BRepPrimAPI_MakePrism, BRepPrimAPI_MakeRevol,
                             BRepPrimAPI_MakeSphere, BRepPrimAPI_MakeTorus)
from OCP.BRepTools import BRepTools
from OCP.Bnd import Bnd_Box
from OCP.GeomAbs import GeomAbs_CurveType, GeomAbs_SurfaceType
from OCP.GeomAPI import GeomAPI_PointsToBSpline, GeomAPI_PointsToBSplineSurface
from OCP.GProp import GProp_GProps
from OCP.Interface import Interface_Static
from OCP.OCP.collections import Array1_gp_Pnt, Array2_gp_Pnt
from OCP.OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_IN, TopAbs_ON, TopAbs_SHELL
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS
from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Pln, gp_Pnt, gp_Pnt2d, gp_Trsf, gp_Vec

ROOT = pathlib.Path(__file__).resolve().parents[2]
# Sample grid per face side; points outside the trims are dropped.
SAMPLES = 16

SURFACE_NAMES = {
    GeomAbs_SurfaceType.GeomAbs_Plane: "plane",
    GeomAbs_SurfaceType.GeomAbs_Cylinder: "cylinder",
    GeomAbs_SurfaceType.GeomAbs_Cone: "cone",
    GeomAbs_SurfaceType.GeomAbs_Sphere: "sphere",
    GeomAbs_SurfaceType.GeomAbs_Torus: "torus",
    GeomAbs_SurfaceType.GeomAbs_BSplineSurface: "bspline",
    GeomAbs_SurfaceType.GeomAbs_BezierSurface: "bezier",
    GeomAbs_SurfaceType.GeomAbs_SurfaceOfExtrusion: "extrusion",
    GeomAbs_SurfaceType.GeomAbs_SurfaceOfRevolution: "revolution",
}


def faces_of(shape):
    m = ShapeMap()
    TopExp.MapShapes_s(shape, TopAbs_FACE, m)
    return [TopoDS.Face(m.FindKey(i)) for i in range(1, m.Extent() + 1)]


def count(shape, kind):
    m = ShapeMap()
    TopExp.MapShapes_s(shape, kind, m)
    return m.Extent()


def face_reference(face):
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    c = props.CentreOfMass()
    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(face, box, False, False)
    lo, hi = box.CornerMin(), box.CornerMax()
    ad = BRepAdaptor_Surface(face)
    umin, umax, vmin, vmax = BRepTools.UVBounds_s(face)
    samples = []
    for i in range(SAMPLES + 1):
        for j in range(SAMPLES + 1):
            u = umin + (umax - umin) * (i + 0.5) / (SAMPLES + 1)
            v = vmin + (vmax - vmin) * (j + 0.5) / (SAMPLES + 1)
            cls = BRepClass_FaceClassifier(face, gp_Pnt2d(u, v), 1e-7)
            if cls.State() == TopAbs_IN:
                p = ad.Value(u, v)
                samples.append([round(p.X(), 7), round(p.Y(), 7), round(p.Z(), 7)])
    return {
        "type": SURFACE_NAMES.get(ad.GetType(), str(ad.GetType())),
        "area_mm2": props.Mass(),
        "centroid": [c.X(), c.Y(), c.Z()],
        "bbox": [[lo.X(), lo.Y(), lo.Z()], [hi.X(), hi.Y(), hi.Z()]],
        "samples": samples,
    }


def write_step(shape, path, unit="MM"):
    w = STEPControl_Writer()
    Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
    Interface_Static.SetCVal_s("write.step.unit", unit)
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    w.Transfer(shape, STEPControl_AsIs)
    w.Write(str(path))


def write_model(name, shape, out, unit="MM"):
    path = out / f"{name}.step"
    write_step(shape, path, unit)
    ref = {
        "model": name,
        "unit": unit.lower(),
        "shells": count(shape, TopAbs_SHELL),
        "faces": [face_reference(f) for f in faces_of(shape)],
        "edges": count(shape, TopAbs_EDGE),
    }
    (out / f"{name}.ref.json").write_text(json.dumps(ref, indent=1) + "\n")
    print(f"{path.name}: {len(ref['faces'])} faces, {ref['edges']} edges, "
          f"{sum(len(f['samples']) for f in ref['faces'])} reference points")


def only_face(shape, kind):
    for f in faces_of(shape):
        if BRepAdaptor_Surface(f).GetType() == kind:
            return f
    raise SystemExit(f"no face of type {kind}")


def dome():
    # z = 40 (1 - r²/80²) sampled on a 9 × 9 grid over [-70, 70]², interpolated bicubically.
    n = 9
    pts = Array2_gp_Pnt(1, n, 1, n)
    for i in range(n):
        for j in range(n):
            x = -70.0 + 140.0 * i / (n - 1)
            y = -70.0 + 140.0 * j / (n - 1)
            pts.SetValue(i + 1, j + 1, gp_Pnt(x, y, 40.0 * (1.0 - (x * x + y * y) / 6400.0)))
    surf = GeomAPI_PointsToBSplineSurface(pts, 3, 3).Surface()
    face = BRepBuilderAPI_MakeFace(surf, 1e-6).Face()
    outer = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -100), gp_Dir(0, 0, 1)), 60.0, 300.0).Shape()
    hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(12, 6, -100), gp_Dir(0, 0, 1)), 14.0, 300.0).Shape()
    trimmed = BRepAlgoAPI_Common(face, outer).Shape()
    return BRepAlgoAPI_Cut(trimmed, hole).Shape()


def cylinder():
    solid = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 30.0, 80.0,
                                     math.radians(150.0)).Shape()
    # Keep what lies below the plane through (0, 0, 50) tilted 25 degrees about the y axis.
    n = gp_Dir(math.sin(math.radians(25.0)), 0.0, math.cos(math.radians(25.0)))
    plane_face = BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(0, 0, 50), n), -200, 200, -200, 200).Face()
    half = BRepPrimAPI_MakeHalfSpace(plane_face, gp_Pnt(0, 0, 200)).Solid()
    cut = BRepAlgoAPI_Cut(solid, half).Shape()
    return only_face(cut, GeomAbs_SurfaceType.GeomAbs_Cylinder)


def cone():
    solid = BRepPrimAPI_MakeCone(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 40.0, 15.0, 50.0).Shape()
    return only_face(solid, GeomAbs_SurfaceType.GeomAbs_Cone)


def torus():
    solid = BRepPrimAPI_MakeTorus(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 50.0, 15.0,
                                  math.radians(-60.0), math.radians(120.0),
                                  math.radians(100.0)).Shape()
    return only_face(solid, GeomAbs_SurfaceType.GeomAbs_Torus)


def sphere_cap():
    solid = BRepPrimAPI_MakeSphere(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 40.0,
                                   math.radians(20.0), math.radians(90.0)).Shape()
    return only_face(solid, GeomAbs_SurfaceType.GeomAbs_Sphere)


def extrusion():
    wave = bspline_through([(0.0, 0.0, 0.0), (20.0, 12.0, 0.0), (40.0, -6.0, 0.0),
                            (60.0, 10.0, 0.0), (80.0, 0.0, 0.0)])
    edge = BRepBuilderAPI_MakeEdge(wave).Edge()
    return BRepPrimAPI_MakePrism(edge, gp_Vec(0.0, 0.0, 60.0)).Shape()


def revolution():
    profile = bspline_through([(30.0, 0.0, 0.0), (42.0, 0.0, 20.0), (28.0, 0.0, 45.0),
                               (35.0, 0.0, 70.0)])
    edge = BRepBuilderAPI_MakeEdge(profile).Edge()
    return BRepPrimAPI_MakeRevol(edge, gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)),
                                 math.radians(270.0)).Shape()


def bspline_through(points):
    arr = Array1_gp_Pnt(1, len(points))
    for i, p in enumerate(points):
        arr.SetValue(i + 1, gp_Pnt(*p))
    return GeomAPI_PointsToBSpline(arr, 3, 3).Curve()


def hull_sections(length=900.0, beam=120.0, depth=70.0, stations=7, side=1.0):
    """Half sections of a hard-chine kayak hull: keel → chine → sheer, at stations along x."""
    secs = []
    for k in range(stations):
        t = k / (stations - 1)
        x = length * t
        # Beam and depth fall off towards bow and stern but never to zero (small end panels).
        w = beam * (0.08 + 0.92 * math.sin(math.pi * t) ** 0.8) / 2.0
        d = depth * (0.35 + 0.65 * math.sin(math.pi * t) ** 0.6)
        rocker = 25.0 * (2.0 * t - 1.0) ** 2
        keel = (x, 0.0, rocker)
        chine = (x, side * 0.75 * w, rocker + 0.25 * d)
        sheer = (x, side * w, rocker + d)
        secs.append((keel, chine, sheer))
    return secs


def hull_half(side):
    secs = hull_sections(side=side)
    loft = BRepOffsetAPI_ThruSections(False, False, 1e-6)
    for keel, chine, sheer in secs:
        mid_bottom = tuple((a + b) / 2.0 for a, b in zip(keel, chine))
        mid_bottom = (mid_bottom[0], mid_bottom[1] * 1.02, mid_bottom[2] - 1.5)
        e1 = BRepBuilderAPI_MakeEdge(bspline_through([keel, mid_bottom, chine])).Edge()
        mid_side = tuple((a + b) / 2.0 for a, b in zip(chine, sheer))
        mid_side = (mid_side[0], mid_side[1] * 1.04, mid_side[2])
        e2 = BRepBuilderAPI_MakeEdge(bspline_through([chine, mid_side, sheer])).Edge()
        loft.AddWire(BRepBuilderAPI_MakeWire(e1, e2).Wire())
    loft.CheckCompatibility(False)
    loft.Build()
    return loft.Shape()


def hull():
    sew = BRepBuilderAPI_Sewing(1e-4)
    sew.Add(hull_half(1.0))
    sew.Add(hull_half(-1.0))
    sew.Perform()
    return sew.SewedShape()


def fillet_box():
    box = BRepPrimAPI_MakeBox(40.0, 30.0, 20.0).Shape()
    f = BRepFilletAPI_MakeFillet(box)
    ex = TopExp_Explorer(box, TopAbs_EDGE)
    f.Add(6.0, TopoDS.Edge(ex.Current()))
    return f.Shape()


def bracket_inch():
    inch = 25.4
    plate = BRepPrimAPI_MakeBox(3.0 * inch, 1.5 * inch, 0.25 * inch).Shape()
    hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0.75 * inch, 0.75 * inch, -1), gp_Dir(0, 0, 1)),
                                    0.25 * inch, 20).Shape()
    slot = BRepPrimAPI_MakeBox(gp_Pnt(1.75 * inch, 0.5 * inch, -1), 0.75 * inch, 0.5 * inch, 20).Shape()
    return BRepAlgoAPI_Cut(BRepAlgoAPI_Cut(plate, hole).Shape(), slot).Shape()


def many_faces(holes_per_side):
    """A 20 mm plate with a grid of through holes, each filleted top and bottom: 6 + 3 n² faces."""
    pitch = 30.0
    size = pitch * holes_per_side
    shape = BRepPrimAPI_MakeBox(size, size, 20.0).Shape()
    tools = []
    for i in range(holes_per_side):
        for j in range(holes_per_side):
            c = gp_Pnt(pitch * (i + 0.5), pitch * (j + 0.5), -5.0)
            tools.append(BRepPrimAPI_MakeCylinder(gp_Ax2(c, gp_Dir(0, 0, 1)), 8.0, 30.0).Shape())
    for t in tools:
        shape = BRepAlgoAPI_Cut(shape, t).Shape()
    f = BRepFilletAPI_MakeFillet(shape)
    ex = TopExp_Explorer(shape, TopAbs_EDGE)
    seen = ShapeMap()
    while ex.More():
        e = TopoDS.Edge(ex.Current())
        if BRepAdaptor_Curve(e).GetType() == GeomAbs_CurveType.GeomAbs_Circle and seen.FindIndex(e) == 0:
            seen.Add(e)
            f.Add(2.0, e)
        ex.Next()
    return f.Shape()


MODELS = {
    "dome": (dome, "MM"),
    "cylinder": (cylinder, "MM"),
    "cone": (cone, "MM"),
    "torus": (torus, "MM"),
    "sphere_cap": (sphere_cap, "MM"),
    "extrusion": (extrusion, "MM"),
    "revolution": (revolution, "MM"),
    "hull": (hull, "MM"),
    "fillet_box": (fillet_box, "MM"),
    "bracket_inch": (bracket_inch, "INCH"),
}


def main():
    if len(sys.argv) >= 2 and sys.argv[1] == "many_faces":
        n, path = int(sys.argv[2]), pathlib.Path(sys.argv[3])
        shape = many_faces(n)
        write_step(shape, path)
        print(f"{path}: {count(shape, TopAbs_FACE)} faces")
        return
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "crates/step/tests/data"
    out.mkdir(parents=True, exist_ok=True)
    for name, (make, unit) in MODELS.items():
        write_model(name, make(), out, unit)


if __name__ == "__main__":
    main()
