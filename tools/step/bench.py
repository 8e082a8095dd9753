#!/usr/bin/env python3
"""Read + tessellate STEP models at one deflection with flatcut and with OpenCASCADE
(cadquery-ocp: STEPControl_Reader + BRepMesh_IncrementalMesh, single-threaded) in one run, and
measure both meshes with the same instrument.

    python3 tools/step/bench.py [--chord 0.1] [--angle 0.5] [--runs 5] MODEL.step…
    (default models: the lofted hull of the tests and a 198-face plate written on the fly)
    python3 tools/step/bench.py --corpus [--out FILE] [--chord 0.1] [--angle 0.5] [--runs 5]
    (every file of crates/step/tests/corpus, one table, written to FILE too)

Accuracy, per mesh, against OCCT's exact faces:
- mesh → surface: the largest distance from the centroid and edge midpoints of every triangle to
  its face's surface (ShapeAnalysis_Surface::ValueOfUV, which finds the global closest point where
  GeomAPI_ProjectPointOnSurf can stop at a local one on the lofted hull);
- surface → mesh: the largest distance from points sampled on every face (inside its trims) to
  that face's triangles.
With `--corpus` the accuracy measures are skipped (they take minutes on the larger files); the
table has, per file: the system that wrote it (manifest.json), faces, flatcut's area (its faces'
trimmed domains) against OCCT's (BRepGProp), repairs, open edges of the welded closed shells,
both times (the fastest of the runs, each side) and their ratio, and both triangle counts.
Each model is also run by flatcut at a chordal tolerance equal to the worst deviation OCCT's mesh
showed (`flatcut @ OCCT accuracy`): the time at equal accuracy. Prints one table; needs the
flatcut example built (`cargo build --release -p flatcut-step
--example step_bench`) or builds it.
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepClass import BRepClass_FaceClassifier
from OCP.BRepGProp import BRepGProp
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPControl import STEPControl_Reader
from OCP.ShapeAnalysis import ShapeAnalysis_Surface
from OCP.TopAbs import TopAbs_IN
from OCP.TopLoc import TopLoc_Location
from OCP.gp import gp_Pnt, gp_Pnt2d

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CORPUS = ROOT / "crates/step/tests/corpus"
sys.path.insert(0, str(HERE))
import make_models  # noqa: E402

SAMPLES = 12


def occt_read(path):
    r = STEPControl_Reader()
    Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
    if r.ReadFile(str(path)) != IFSelect_RetDone:
        raise SystemExit(f"OCCT cannot read {path}")
    r.TransferRoots()
    return r.OneShape()


def occt_time(path, chord, runs, angle, stat=statistics.median):
    times = []
    shape = None
    for _ in range(runs):
        t0 = time.perf_counter()
        shape = occt_read(path)
        BRepMesh_IncrementalMesh(shape, chord, False, angle, False)
        times.append(time.perf_counter() - t0)
    return stat(times), shape


def occt_mesh(face):
    loc = TopLoc_Location()
    tri = BRep_Tool.Triangulation_s(face, loc)
    if tri is None:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=int)
    trsf = loc.Transformation()
    pts = np.array([[p.X(), p.Y(), p.Z()] for p in
                    (tri.Node(i).Transformed(trsf) for i in range(1, tri.NbNodes() + 1))])
    tris = np.array([[t.Value(1) - 1, t.Value(2) - 1, t.Value(3) - 1] for t in
                     (tri.Triangle(i) for i in range(1, tri.NbTriangles() + 1))])
    return pts, tris


def read_obj(path):
    verts, groups, cur = [], {}, None
    for line in open(path):
        if line.startswith("v "):
            verts.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("g "):
            cur = line.split()[1]
            groups[cur] = []
        elif line.startswith("f "):
            groups[cur].append([int(x) - 1 for x in line.split()[1:4]])
    v = np.array(verts)
    out = []
    for tris in groups.values():
        t = np.array(tris)
        used = np.unique(t)
        remap = -np.ones(len(v), dtype=int)
        remap[used] = np.arange(len(used))
        out.append((v[used], remap[t]))
    return out


def face_samples(face):
    ad = BRepAdaptor_Surface(face)
    umin, umax, vmin, vmax = BRepTools.UVBounds_s(face)
    pts = []
    for i in range(SAMPLES + 1):
        for j in range(SAMPLES + 1):
            u = umin + (umax - umin) * (i + 0.5) / (SAMPLES + 1)
            v = vmin + (vmax - vmin) * (j + 0.5) / (SAMPLES + 1)
            if BRepClass_FaceClassifier(face, gp_Pnt2d(u, v), 1e-7).State() == TopAbs_IN:
                p = ad.Value(u, v)
                pts.append([p.X(), p.Y(), p.Z()])
    return np.array(pts).reshape(-1, 3)


def point_triangle_distances(p, a, b, c):
    """Distances from points p (n,3) to triangles (m,3 each): (n,) minimum over triangles."""
    best = np.full(len(p), np.inf)
    for k in range(0, len(a), 2048):
        A, B, C = a[k:k + 2048], b[k:k + 2048], c[k:k + 2048]
        # Closest point by projecting onto the plane and clamping with barycentric fallback to
        # segments (exact for points whose projection lies inside; edges handled below).
        ab, ac = B - A, C - A
        n = np.cross(ab, ac)
        nn = np.einsum("ij,ij->i", n, n)
        ok = nn > 0
        for i in range(len(p)):
            ap = p[i] - A
            d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
            bp = p[i] - B
            d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
            cp = p[i] - C
            d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
            va = d3 * d6 - d5 * d4
            vb = d5 * d2 - d1 * d6
            vc = d1 * d4 - d3 * d2
            denom = np.where(va + vb + vc == 0, 1, va + vb + vc)
            v = vb / denom
            w = vc / denom
            q = A + ab * v[:, None] + ac * w[:, None]
            inside = (va >= 0) & (vb >= 0) & (vc >= 0) & ok
            dist = np.where(inside, np.linalg.norm(q - p[i], axis=1), np.inf)
            # Edges.
            for s0, s1 in ((A, B), (B, C), (C, A)):
                e = s1 - s0
                ee = np.einsum("ij,ij->i", e, e)
                t = np.clip(np.einsum("ij,ij->i", p[i] - s0, e) / np.where(ee == 0, 1, ee), 0, 1)
                dist = np.minimum(dist, np.linalg.norm(s0 + e * t[:, None] - p[i], axis=1))
            best[i] = min(best[i], dist.min())
    return best


def accuracy(shape_faces, meshes):
    """(mesh → surface, surface → mesh) worst distances over all faces; meshes matched to faces
    by centre of area."""
    centres = []
    for v, t in meshes:
        if len(t) == 0:
            centres.append(np.full(3, np.inf))
            continue
        a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
        ar = np.linalg.norm(np.cross(b - a, c - a), axis=1) / 2
        centres.append(((a + b + c) / 3 * ar[:, None]).sum(0) / ar.sum())
    centres = np.array(centres)
    worst_ms, worst_sm = 0.0, 0.0
    for face in shape_faces:
        props = GProp_GProps()
        BRepGProp.SurfaceProperties_s(face, props)
        c = props.CentreOfMass()
        k = int(np.argmin(np.linalg.norm(centres - [c.X(), c.Y(), c.Z()], axis=1)))
        v, t = meshes[k]
        if len(t) == 0:
            continue
        sas = ShapeAnalysis_Surface(BRep_Tool.Surface_s(face))
        a, b, cc = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
        probes = np.concatenate([(a + b + cc) / 3, (a + b) / 2, (b + cc) / 2, (cc + a) / 2])
        for q in probes:
            sas.ValueOfUV(gp_Pnt(*q), 1e-9)
            worst_ms = max(worst_ms, sas.Gap())
        s = face_samples(face)
        if len(s):
            worst_sm = max(worst_sm, point_triangle_distances(s, a, b, cc).max())
    return worst_ms, worst_sm


def occt_area(faces):
    """The area of the distinct faces (a file listing one shell in several representations
    transfers it more than once), as make_corpus.py's reference."""
    total = 0.0
    for f in faces:
        props = GProp_GProps()
        BRepGProp.SurfaceProperties_s(f, props)
        total += props.Mass()
    return total


def build_example():
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "flatcut-step", "--example", "step_bench"],
                   cwd=ROOT, check=True)
    return ROOT / "target/release/examples/step_bench"


def corpus(args):
    """One run over every corpus file: the table of the issue's closing note."""
    manifest = json.loads((CORPUS / "manifest.json").read_text())["files"]
    exe = build_example()
    rows = []
    for e in manifest:
        path = CORPUS / e["file"]
        occt_s, shape = occt_time(path, args.chord, args.runs, args.angle, min)
        faces = make_models.faces_of(shape)
        n_occt = sum(len(t) for _, t in (occt_mesh(f) for f in faces))
        area = occt_area(faces)
        out = subprocess.run([str(exe), "--chord", str(args.chord), "--angle", str(args.angle),
                              "--runs", str(args.runs), str(path)],
                             check=True, capture_output=True, text=True).stdout.splitlines()[-1]
        run = json.loads(out)
        if "min_seconds" in run:
            run["seconds"] = run["min_seconds"]
        rows.append((e, len(faces), area, n_occt, occt_s, run))
        print(f"{e['file']}: {run.get('seconds', run.get('error'))} s, OCCT {occt_s:.4f} s",
              file=sys.stderr, flush=True)
    lines = [f"Read + tessellate at deflection {args.chord} mm and {args.angle} rad, fastest of {args.runs} runs "
             "(the machine is shared: the fastest run is the least disturbed), one thread, "
             "flatcut (step_bench) against OCCT (STEPControl_Reader + BRepMesh_IncrementalMesh), "
             "one run of tools/step/bench.py --corpus.",
             "",
             "| file | system | faces | area error | repairs | open edges | flatcut s | OCCT s "
             "| time ratio | triangles | OCCT triangles |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    ratios = []
    for e, nf, area, n_occt, occt_s, run in rows:
        if "error" in run:
            lines.append(f"| {e['file']} | {e['system']} | {nf} | refused: {run['error']} | | | | "
                         f"{occt_s:.4f} | | | {n_occt} |")
            continue
        err = (run["area_mm2"] - area) / area if area else float("nan")
        ratio = run["seconds"] / occt_s
        ratios.append(ratio)
        lines.append(f"| {e['file']} | {e['system']} | {run['faces']} | {err:+.2e} | {run['repairs']} "
                     f"| {run['open_edges']} | {run['seconds']:.4f} | {occt_s:.4f} | {ratio:.2f} "
                     f"| {run['triangles']} | {n_occt} |")
    if ratios:
        lines += ["", f"{len(ratios)} files read; time ratio (flatcut / OCCT): median "
                  f"{statistics.median(ratios):.2f}, worst {max(ratios):.2f}, "
                  f"{sum(r > 1 for r in ratios)} files slower than OCCT."]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        pathlib.Path(args.out).write_text(text)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--chord", type=float, default=0.1)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--angle", type=float, default=0.5,
                    help="angular deflection (rad) of both meshers: BRepMesh's, and flatcut's "
                         "largest normal turn across a triangle")
    ap.add_argument("--corpus", action="store_true")
    ap.add_argument("--out")
    ap.add_argument("models", nargs="*")
    args = ap.parse_args()
    if args.corpus:
        return corpus(args)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="flatcut-step-bench-"))
    models = [pathlib.Path(m) for m in args.models]
    if not models:
        plate = tmp / "plate198.step"
        make_models.write_step(make_models.many_faces(8), plate)
        models = [ROOT / "crates/step/tests/data/hull.step", plate]
    exe = build_example()
    def ours(model, chord):
        out = subprocess.run(
            [str(exe), "--chord", str(chord), "--angle", str(args.angle), "--runs", str(args.runs),
             "--obj", str(tmp), str(model)],
            check=True, capture_output=True, text=True).stdout.splitlines()[-1]
        return json.loads(out), read_obj(tmp / f"{model.stem}.obj")

    rows = []
    for m in models:
        occt_s, shape = occt_time(m, args.chord, args.runs, args.angle)
        faces = make_models.faces_of(shape)
        occt_meshes = [occt_mesh(f) for f in faces]
        acc_occt = accuracy(faces, occt_meshes)
        n_occt = sum(len(t) for _, t in occt_meshes)
        rows.append((m.name, "OCCT", args.chord, len(faces), occt_s, occt_s, n_occt, acc_occt))
        for chord in (args.chord, max(acc_occt)):
            run, meshes = ours(m, chord)
            rows.append((m.name, "flatcut", chord, len(faces), run["seconds"], occt_s,
                         run["triangles"], accuracy(faces, meshes)))
    print(f"\ndeflection {args.chord} mm for OCCT, angle {args.angle} rad for both; median of {args.runs} runs, one thread")
    print("| model | mesher | chord mm | faces | seconds | ratio to OCCT | triangles "
          "| mesh→surface mm | surface→mesh mm |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, who, chord, nf, t, to, nt, (a1, a2) in rows:
        print(f"| {name} | {who} | {chord:.4f} | {nf} | {t:.4f} | {t / to:.2f} | {nt} "
              f"| {a1:.4f} | {a2:.4f} |")


if __name__ == "__main__":
    main()
