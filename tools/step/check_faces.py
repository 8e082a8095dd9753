#!/usr/bin/env python3
"""Face by face against OpenCASCADE: for the faces of a STEP file that flatcut repaired (by
default those whose orientation it reversed; `--all` every face), the area on the face's trimmed
domain against OCCT's face (BRepGProp), and the normals of flatcut's mesh against OCCT's face
normal (the surface normal, reversed where OCCT's face is REVERSED) at points inside the face.

    python3 tools/step/check_faces.py [--all] [--chord 0.1] FILE.step

Faces are matched by their centre of area and area (OCCT does not keep the STEP `#id` of a
face). Where a closed form gives a face's exact area (`exact_area.py`: planes and spheres bounded
by lines, circles and ellipses), it is printed beside, with each side's error, and an area
disagreement that the exact figure puts on OCCT's side is reported as such ("OCCT is off"), not
counted. Prints one line per face and exits 1 if any face disagrees: an area off by more than
0.1 %, or a normal pointing the other way at any sample point. Needs the flatcut example built
(`cargo build --release -p flatcut-step --example step_bench`) or builds it.
"""

import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepClass import BRepClass_FaceClassifier
from OCP.BRepGProp import BRepGProp
from OCP.BRepTools import BRepTools
from OCP.GProp import GProp_GProps
from OCP.TopAbs import TopAbs_IN, TopAbs_REVERSED
from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))
import bench  # noqa: E402
import exact_area  # noqa: E402
import make_models  # noqa: E402

SAMPLES = 16
AREA_REL = 1e-3


def occt_face(face):
    """Area, centre of area, and (points, outward normals as OCCT orients the face) inside it."""
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    c = props.CentreOfMass()
    ad = BRepAdaptor_Surface(face)
    flip = face.Orientation() == TopAbs_REVERSED
    umin, umax, vmin, vmax = BRepTools.UVBounds_s(face)
    pts, nrm = [], []
    for i in range(SAMPLES):
        for j in range(SAMPLES):
            u = umin + (umax - umin) * (i + 0.5) / SAMPLES
            v = vmin + (vmax - vmin) * (j + 0.5) / SAMPLES
            if BRepClass_FaceClassifier(face, gp_Pnt2d(u, v), 1e-7).State() != TopAbs_IN:
                continue
            p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
            ad.D1(u, v, p, du, dv)
            n = du.Crossed(dv)
            if n.Magnitude() < 1e-12:
                continue
            n.Normalize()
            if flip:
                n.Reverse()
            pts.append([p.X(), p.Y(), p.Z()])
            nrm.append([n.X(), n.Y(), n.Z()])
    return props.Mass(), np.array([c.X(), c.Y(), c.Z()]), np.array(pts).reshape(-1, 3), \
        np.array(nrm).reshape(-1, 3)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--all", action="store_true")
    ap.add_argument("--chord", type=float, default=0.1)
    ap.add_argument("model")
    args = ap.parse_args()
    path = pathlib.Path(args.model)
    exe = bench.build_example()
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="flatcut-check-faces-"))
    subprocess.run([str(exe), "--chord", str(args.chord), "--runs", "1", "--obj", str(tmp), str(path)],
                   check=True, capture_output=True)
    meshes = bench.read_obj(tmp / f"{path.stem}.obj")
    ours = json.loads((tmp / f"{path.stem}.faces.json").read_text())
    shape = bench.occt_read(path)
    faces = [occt_face(f) for f in make_models.faces_of(shape)]
    centres = np.array([f[1] for f in faces])
    areas = np.array([f[0] for f in faces])
    entities = exact_area.load(path)
    # The exact areas are in the file's units; flatcut and OCCT give mm².
    unit2 = 25.4 ** 2 if "CONVERSION_BASED_UNIT('INCH'" in path.read_text(errors="replace") else 1.0
    bad = 0
    checked = 0
    for info, (v, t) in zip(ours, meshes):
        kinds = [r["kind"] for r in info["repairs"]]
        if not args.all and "orientation" not in kinds:
            continue
        checked += 1
        a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
        cross = np.cross(b - a, c - a)
        tri_area = np.linalg.norm(cross, axis=1) / 2
        centre = ((a + b + c) / 3 * tri_area[:, None]).sum(0) / tri_area.sum()
        # The OCCT face nearest in centre and area.
        score = np.linalg.norm(centres - centre, axis=1) / max(1.0, np.sqrt(info["area_mm2"])) \
            + np.abs(areas - info["area_mm2"]) / max(info["area_mm2"], 1e-12)
        k = int(np.argmin(score))
        area, _, pts, nrm = faces[k]
        rel = (info["area_mm2"] - area) / area
        # Our normal at each OCCT sample: that of the nearest triangle.
        tc = (a + b + c) / 3
        unit = cross / np.maximum(np.linalg.norm(cross, axis=1), 1e-300)[:, None]
        against = 0
        for p, n in zip(pts, nrm):
            j = int(np.argmin(np.linalg.norm(tc - p, axis=1)))
            if np.dot(unit[j], n) < 0:
                against += 1
        area_ok = abs(rel) <= AREA_REL
        ok = area_ok and against == 0 and len(pts) > 0
        exact = exact_area.exact_area(entities, info["entity"])
        note = ""
        if exact is not None:
            e = exact[1] * unit2
            ours_e, occt_e = (info["area_mm2"] - e) / e, (area - e) / e
            note = f"; exact {e:.4f} (flatcut {ours_e:+.1e}, OCCT {occt_e:+.1e})"
            if not area_ok and abs(ours_e) <= AREA_REL < abs(occt_e):
                ok = against == 0 and len(pts) > 0
                note += ", OCCT is off"
        bad += not ok
        print(f"face {info['face']} (#{info['entity']}, {info['surface']}): area {info['area_mm2']:.4f} mm², "
              f"OCCT {area:.4f} ({rel:+.2e}){note}; normals against OCCT's at {against} of {len(pts)} points; "
              f"repairs {', '.join(kinds) or 'none'}: {'agrees' if ok else 'DISAGREES'}")
    print(f"{checked} faces checked, {bad} disagree")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
