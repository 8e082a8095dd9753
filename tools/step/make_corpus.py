#!/usr/bin/env python3
"""Writes the OpenCASCADE-made models of the STEP corpus (crates/step/tests/corpus) and, for every
STEP file there, the figures OpenCASCADE gives for it: the oracle of crates/step/tests/corpus.rs.

    python3 tools/step/make_corpus.py models [DIR]     writes occt_*.step (the issue's cases)
    python3 tools/step/make_corpus.py reference [DIR]  writes DIR/reference.json
    python3 tools/step/make_corpus.py reference DIR FILE…  adds those files' entries to it

The models are the kinds every CAD system writes and flatcut once got wrong: spheres cut every
way (the trim loop runs along the seam to the pole and back, no pole edge), a blind and a through
hole across the seam, a box with every edge filleted (cylinders meeting sphere corners), a
sphere cut across its seam (a disk sewn to its rim), chamfers, revolved and lofted shells, in mm
and inch, AP203/AP214/AP242. The reference holds, per file, what OCCT's STEPControl_Reader reads
(after its own ShapeFix healing): the number of faces, the total area (BRepGProp), whether
BRepCheck finds the shape valid, the closed shells, and the time OCCT takes to read and mesh it
(BRepMesh at the deflection the test uses).
"""

import json
import math
import pathlib
import sys
import time

from OCP.BRepAlgoAPI import BRepAlgoAPI_Common, BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepFilletAPI import BRepFilletAPI_MakeChamfer, BRepFilletAPI_MakeFillet
from OCP.BRepGProp import BRepGProp
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepPrimAPI import (BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCone,
                             BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakeHalfSpace,
                             BRepPrimAPI_MakeSphere, BRepPrimAPI_MakeTorus)
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader, STEPControl_Writer
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS
from OCP.gp import gp_Ax2, gp_Dir, gp_Pln, gp_Pnt

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORPUS = ROOT / "crates/step/tests/corpus"
# The chordal deflection of the test (mm): OCCT meshes at the same one for the time ratio.
DEFLECTION = 0.1


def half_space(point, normal, keep):
    face = BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(*point), gp_Dir(*normal)), -1e3, 1e3, -1e3, 1e3).Face()
    return BRepPrimAPI_MakeHalfSpace(face, gp_Pnt(*keep)).Solid()


def sphere():
    return BRepPrimAPI_MakeSphere(gp_Pnt(0, 0, 0), 100.0).Shape()


def sphere_cut():
    """R 100 cut at z = 50: the part below (94,248 + 23,562 = 117,810 mm²)."""
    return BRepAlgoAPI_Cut(sphere(), half_space((0, 0, 50), (0, 0, 1), (0, 0, 500))).Shape()


def sphere_cut_y():
    """R 100 cut at y = 50 (across the seam): a disk sewn to the sphere's rim."""
    return BRepAlgoAPI_Cut(sphere(), half_space((0, 50, 0), (0, 1, 0), (0, 500, 0))).Shape()


def sphere_blind_hole():
    """The cut sphere with a blind hole from the seam side (+x) along x."""
    drill = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(150, 0, -20), gp_Dir(-1, 0, 0)), 15.0, 100.0).Shape()
    return BRepAlgoAPI_Cut(sphere_cut(), drill).Shape()


def sphere_through_hole():
    """The cut sphere with a through hole along x, across the seam on one side."""
    drill = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(150, 0, -20), gp_Dir(-1, 0, 0)), 15.0, 300.0).Shape()
    return BRepAlgoAPI_Cut(sphere_cut(), drill).Shape()


def all_edges(shape):
    m = ShapeMap()
    TopExp.MapShapes_s(shape, TopAbs_EDGE, m)
    return [TopoDS.Edge(m.FindKey(i)) for i in range(1, m.Extent() + 1)]


def every_edge(maker, size):
    """A 60 × 40 × 30 box with every edge rounded or bevelled by `maker` (fillet or chamfer)."""
    box = BRepPrimAPI_MakeBox(60.0, 40.0, 30.0).Shape()
    f = maker(box)
    for e in all_edges(box):
        f.Add(size, e)
    return f.Shape()


def box_filleted():
    """Every edge filleted R 6: planes, cylinders, sphere corners."""
    return every_edge(BRepFilletAPI_MakeFillet, 6.0)


def box_chamfered():
    return every_edge(BRepFilletAPI_MakeChamfer, 4.0)


def torus_full():
    return BRepPrimAPI_MakeTorus(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 50.0, 15.0).Shape()


def torus_halves(keep_outer):
    """A torus (R 50, r 15) cut by the cylinder through its tube's crest: the outer half's torus
    face runs across v = 0, its loops at v = 3pi/2 and pi/2 (the band between them is the one
    the orientation names, a period up, not the inner one); the inner half's does not."""
    torus = BRepPrimAPI_MakeTorus(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 50.0, 15.0).Shape()
    cyl = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -50), gp_Dir(0, 0, 1)), 50.0, 100.0).Shape()
    if keep_outer:
        return BRepAlgoAPI_Cut(torus, cyl).Shape()
    return BRepAlgoAPI_Common(torus, cyl).Shape()


def cylinder_panels():
    """A tube (R 30, 80 long) as two half-cylinder sheets, each its own open shell: their
    edges along the two lines where they meet are separate edges, to be sewn."""
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound, TopoDS_Shell
    from OCP.gp import gp_Cylinder, gp_Ax3
    cyl = gp_Cylinder(gp_Ax3(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 30.0)
    builder = BRep_Builder()
    compound = TopoDS_Compound()
    builder.MakeCompound(compound)
    for u0, u1 in [(0.0, math.pi), (math.pi, 2.0 * math.pi)]:
        face = BRepBuilderAPI_MakeFace(cyl, u0, u1, 0.0, 80.0).Face()
        shell = TopoDS_Shell()
        builder.MakeShell(shell)
        builder.Add(shell, face)
        builder.Add(compound, shell)
    return compound


def cone_apex():
    """A cone to its apex, cut by an inclined plane."""
    cone = BRepPrimAPI_MakeCone(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 40.0, 0.0, 60.0).Shape()
    return BRepAlgoAPI_Cut(cone, half_space((0, 0, 10), (0.3, 0, 1), (0, 0, -500))).Shape()


def cylinder_sphere():
    """A capsule: a cylinder fused with a sphere at each end."""
    c = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 20.0, 80.0).Shape()
    a = BRepPrimAPI_MakeSphere(gp_Pnt(0, 0, 0), 20.0).Shape()
    b = BRepPrimAPI_MakeSphere(gp_Pnt(0, 0, 80), 20.0).Shape()
    return BRepAlgoAPI_Fuse(BRepAlgoAPI_Fuse(c, a).Shape(), b).Shape()


def pipe_tee():
    """Pipes on three axes: a main pipe (R 20 along z) with a branch along x (R 12) and one at
    45 degrees in the y-z plane (R 8). Each junction is a cylinder meeting a cylinder on another
    axis: the rulings of each cross the other's edges."""
    main = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -60), gp_Dir(0, 0, 1)), 20.0, 120.0).Shape()
    tee = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(1, 0, 0)), 12.0, 60.0).Shape()
    skew = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 20), gp_Dir(0, 1, 1)), 8.0, 60.0).Shape()
    return BRepAlgoAPI_Fuse(BRepAlgoAPI_Fuse(main, tee).Shape(), skew).Shape()


def assembly(path):
    """One box placed three times by an assembly (XCAF: NEXT_ASSEMBLY_USAGE_OCCURRENCE and
    CONTEXT_DEPENDENT_SHAPE_REPRESENTATION with ITEM_DEFINED_TRANSFORMATIONs), the third turned
    30 degrees about z."""
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDocStd import TDocStd_Document
    from OCP.TopLoc import TopLoc_Location
    from OCP.XCAFDoc import XCAFDoc_DocumentTool
    from OCP.gp import gp_Ax1, gp_Trsf, gp_Vec
    box = BRepPrimAPI_MakeBox(40.0, 30.0, 20.0).Shape()
    doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    top = tool.NewShape()
    part = tool.AddShape(box, False)
    for dx, angle in [(0.0, 0.0), (40.0, 0.0), (100.0, 30.0)]:
        turn = gp_Trsf()
        turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), math.radians(angle))
        move = gp_Trsf()
        move.SetTranslation(gp_Vec(dx, 0.0, 0.0))
        tool.AddComponent(top, part, TopLoc_Location(move.Multiplied(turn)))
    tool.UpdateAssemblies()
    w = STEPCAFControl_Writer()
    w.Transfer(doc, STEPControl_AsIs)
    w.Write(str(path))


MODELS = {
    "occt_sphere_cut": (sphere_cut, "MM", "AP214IS"),
    "occt_sphere_cut_y": (sphere_cut_y, "MM", "AP214IS"),
    "occt_sphere_blind_hole": (sphere_blind_hole, "MM", "AP214IS"),
    "occt_sphere_through_hole": (sphere_through_hole, "MM", "AP214IS"),
    "occt_box_filleted": (box_filleted, "MM", "AP203"),
    "occt_box_chamfered": (box_chamfered, "INCH", "AP242DIS"),
    "occt_torus": (torus_full, "MM", "AP214IS"),
    "occt_cone_apex": (cone_apex, "MM", "AP203"),
    "occt_torus_outer": (lambda: torus_halves(True), "MM", "AP214IS"),
    "occt_cylinder_panels": (cylinder_panels, "MM", "AP214IS"),
    "occt_torus_inner": (lambda: torus_halves(False), "MM", "AP242DIS"),
    "occt_capsule": (cylinder_sphere, "MM", "AP242DIS"),
    "occt_pipe_tee": (pipe_tee, "MM", "AP214IS"),
}


def write(shape, path, unit, schema):
    w = STEPControl_Writer()
    Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
    Interface_Static.SetCVal_s("write.step.unit", unit)
    Interface_Static.SetCVal_s("write.step.schema", schema)
    w.Transfer(shape, STEPControl_AsIs)
    w.Write(str(path))


def count(shape, kind):
    m = ShapeMap()
    TopExp.MapShapes_s(shape, kind, m)
    return m.Extent()


def reference(path):
    t0 = time.perf_counter()
    r = STEPControl_Reader()
    Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
    if r.ReadFile(str(path)) != IFSelect_RetDone:
        return {"read": False}
    r.TransferRoots()
    shape = r.OneShape()
    t_read = time.perf_counter() - t0
    t0 = time.perf_counter()
    BRepMesh_IncrementalMesh(shape, DEFLECTION, False, 0.5, False)
    t_mesh = time.perf_counter() - t0
    # The area of the distinct faces: a file that lists one shell in several representations
    # (a presentation model beside the shape) transfers it more than once.
    area = 0.0
    moment = [0.0, 0.0, 0.0]
    faces = ShapeMap()
    TopExp.MapShapes_s(shape, TopAbs_FACE, faces)
    for i in range(1, faces.Extent() + 1):
        props = GProp_GProps()
        BRepGProp.SurfaceProperties_s(faces.FindKey(i), props)
        area += props.Mass()
        c = props.CentreOfMass()
        for k, x in enumerate((c.X(), c.Y(), c.Z())):
            moment[k] += props.Mass() * x
    closed = 0
    ex = TopExp_Explorer(shape, TopAbs_SHELL)
    while ex.More():
        closed += int(BRep_Tool_closed(ex.Current()))
        ex.Next()
    return {
        "read": True,
        "faces": count(shape, TopAbs_FACE),
        "area_mm2": area,
        "centroid": [round(m / area, 6) for m in moment] if area > 0 else None,
        "valid": BRepCheck_Analyzer(shape).IsValid(),
        "shells": count(shape, TopAbs_SHELL),
        "closed_shells": closed,
        "occt_seconds": round(t_read + t_mesh, 4),
        "occt_triangles": triangles(faces),
    }


def triangles(faces):
    """The triangles of OCCT's mesh of the distinct faces (BRepMesh at the test's deflection)."""
    from OCP.BRep import BRep_Tool
    from OCP.TopLoc import TopLoc_Location
    n = 0
    for i in range(1, faces.Extent() + 1):
        tri = BRep_Tool.Triangulation_s(TopoDS.Face(faces.FindKey(i)), TopLoc_Location())
        n += 0 if tri is None else tri.NbTriangles()
    return n


def BRep_Tool_closed(shell):
    from OCP.BRep import BRep_Tool
    return BRep_Tool.IsClosed_s(shell)


def main():
    mode = sys.argv[1] if len(sys.argv) > 1 else "reference"
    out = pathlib.Path(sys.argv[2]) if len(sys.argv) > 2 else CORPUS
    out.mkdir(parents=True, exist_ok=True)
    if mode == "models":
        for name, (make, unit, schema) in MODELS.items():
            shape = make()
            write(shape, out / f"{name}.step", unit, schema)
            print(f"{name}: {count(shape, TopAbs_FACE)} faces, valid {BRepCheck_Analyzer(shape).IsValid()}")
        assembly(out / "occt_assembly.step")
        return
    only = sys.argv[3:]
    refs = json.loads((out / "reference.json").read_text()) if only else {}
    for p in sorted(out.iterdir()):
        if p.suffix.lower() in (".step", ".stp") and (not only or p.name in only):
            refs[p.name] = reference(p)
            print(p.name, refs[p.name])
    (out / "reference.json").write_text(json.dumps(refs, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
