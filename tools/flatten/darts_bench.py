#!/usr/bin/env python3
"""Automatic darts and splits against OptCuts in one run: per mesh, the cuts each needs to bring
the map within a stretch/compression limit, the total cut length, the worst principal stretches measured
by the bench's metrics.py (not by either tool's own report), flips, and time.

usage: python darts_bench.py --bench ../shared/bench --flatcut target/release/flatcut
                             [--optcuts OptCuts_bin] [--optcuts-limits S C]
                             [--stretch 3] [--compress 3] [--timeout S] [--out DIR] MESH.obj...

flatcut runs `flatten MESH --darts auto --split auto --max-stretch S --max-compress C` (darts
first; a piece no dart can help, as a saddle, is split into parts); its cut length is the darts'
3D length plus the new seams' from its report. OptCuts (Li et al. 2018) runs headless with its own setting:
the bound is on the area-weighted mean symmetric Dirichlet energy, so the equivalent of a
per-face limit is the energy of a face stretched by S along one axis and compressed by C across,
s² + s⁻² + c² + c⁻² with s = 1 + S/100, c = 1 − C/100. A mean bound does not hold every face,
which is why the table counts the faces beyond the limits for both. `--optcuts-limits S C`
gives OptCuts the bound of other (tighter) limits, to find the bound at which its result, too,
holds every face within --stretch/--compress. OptCuts' cut length is the 3D length of the
interior edges whose two sides have different UV.
"""
import argparse
import glob
import resource
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections import defaultdict

import numpy as np


def load_obj(path):
    """v, f with their vt (a face without texture indices uses its vertex indices)."""
    V, T, F, FT = [], [], [], []
    with open(path) as f:
        for line in f:
            s = line.split()
            if not s:
                continue
            if s[0] == "v":
                V.append([float(x) for x in s[1:4]])
            elif s[0] == "vt":
                T.append([float(x) for x in s[1:3]])
            elif s[0] == "f":
                c = [tok.split("/") for tok in s[1:4]]
                F.append([int(a[0]) - 1 for a in c])
                FT.append([int(a[1]) - 1 if len(a) > 1 and a[1] else int(a[0]) - 1 for a in c])
    return np.array(V), np.array(F), np.array(T), np.array(FT)


def measure(bench, paths, stretch, compress):
    """Worst stretch and compression (%), faces beyond the limits, flips, and the length (mm) of
    the cuts inside each OBJ (the parts of a split piece are OBJs of their own)."""
    sys.path.insert(0, bench)
    import metrics  # noqa: E402

    parts = [one(metrics, p, stretch, compress) for p in paths]
    return {
        "stretch_max_pct": max(r["stretch_max_pct"] for r in parts),
        "compress_max_pct": max(r["compress_max_pct"] for r in parts),
        "faces_over": sum(r["faces_over"] for r in parts),
        "faces": sum(r["faces"] for r in parts),
        "flips": sum(r["flips"] for r in parts),
        "cut_mm": sum(r["cut_mm"] for r in parts),
        "parts": len(parts),
    }


def one(metrics, path, stretch, compress):
    V, F, T, FT = load_obj(path)
    s1, s2, _, _, A2 = metrics.singular_values(V, F, T, FT)
    sign = np.sign(A2.sum())
    over = int(((s1 > 1 + stretch / 100 + 1e-9) | (s2 < 1 - compress / 100 - 1e-9)).sum())
    sides = defaultdict(set)
    for f in range(len(F)):
        for k in range(3):
            a, b = F[f][k], F[f][(k + 1) % 3]
            ua, ub = FT[f][k], FT[f][(k + 1) % 3]
            sides[(min(a, b), max(a, b))].add((ua, ub) if a < b else (ub, ua))
    cut = sum(np.linalg.norm(V[a] - V[b]) for (a, b), s in sides.items() if len(s) == 2)
    return {
        "stretch_max_pct": 100 * (s1.max() - 1),
        "compress_max_pct": 100 * (1 - s2.min()),
        "faces_over": over,
        "faces": len(F),
        "flips": int(((A2 * sign) <= 0).sum()),
        "cut_mm": cut,
    }


def children_cpu():
    """CPU seconds (user + system) of the finished child processes so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def genus(path):
    """Genus of a closed connected OBJ surface, from its Euler characteristic."""
    V, F, _, _ = load_obj(path)
    edges = {(min(a, b), max(a, b)) for t in F for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    return (2 - (len(V) - len(edges) + len(F))) // 2


def run_flatcut(binary, mesh, out, stretch, compress, timeout, extra=()):
    obj, rep = os.path.join(out, "flatcut.obj"), os.path.join(out, "flatcut.json")
    cmd = [binary, "flatten", mesh, "-o", obj, "--report", rep, "--darts", "auto", "--split", "auto",
           "--max-stretch", str(stretch), "--max-compress", str(compress)] + list(extra)
    t0, c0 = time.monotonic(), children_cpu()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"no result in {timeout} s"}
    dt, cpu = time.monotonic() - t0, children_cpu() - c0
    objs = [obj] if os.path.exists(obj) else sorted(glob.glob(os.path.join(out, "flatcut-*.obj")))
    if p.returncode != 0 or not objs:
        return {"error": p.stderr.strip().splitlines()[-1] if p.stderr.strip() else f"exit {p.returncode}",
                "seconds": dt, "cpu": cpu}
    report = json.load(open(rep))
    reports = report if isinstance(report, list) else [report]
    darts = [d for r in reports for d in r.get("darts", [])]
    seams = {s["name"]: s["length_3d_mm"] for r in reports for s in r.get("mating_seams", [])}
    return {"obj": objs, "seconds": dt, "cpu": cpu, "cuts": len(darts) + len(seams),
            "darts": len(darts), "seams": len(seams),
            "mouths_mm": sum(d.get("opening_mm", 0.0) for d in darts),
            "dart_mm": sum(d["length_3d_mm"] for d in darts) + sum(seams.values())}


def run_optcuts(binary, mesh, out, stretch, compress, timeout):
    s, c = 1 + stretch / 100, 1 - compress / 100
    bound = s * s + 1 / (s * s) + c * c + 1 / (c * c)
    name = "input"
    V, F, _, _ = load_obj(mesh)
    with open(os.path.join(out, name + ".obj"), "w") as f:  # no vt: OptCuts would start from it
        for v in V:
            f.write("v %.17g %.17g %.17g\n" % tuple(v))
        for t in F:
            f.write("f %d %d %d\n" % tuple(t + 1))
    # progMode 100: headless optimisation; λ 0.999, method 1 (OptCuts), bound, bijectivity on
    cmd = [binary, "100", name + ".obj", "0.999", "1", "0", "%.6f" % bound, "1", "0"]
    t0, c0 = time.monotonic(), children_cpu()
    try:
        p = subprocess.run(cmd, cwd=out, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"no result in {timeout} s", "bound": bound}
    dt, cpu = time.monotonic() - t0, children_cpu() - c0
    found = glob.glob(os.path.join(out, "output", name + "_*", "finalResult_mesh.obj"))
    if not found:
        return {"error": f"exit {p.returncode}, no finalResult_mesh.obj", "seconds": dt, "cpu": cpu, "bound": bound}
    return {"obj": found, "seconds": dt, "cpu": cpu, "bound": bound}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", required=True)
    ap.add_argument("--flatcut", required=True)
    ap.add_argument("--flatcut-args", default="",
                    help="more arguments for flatcut, e.g. '--dart-fit tight'")
    ap.add_argument("--optcuts")
    ap.add_argument("--optcuts-limits", nargs=2, type=float, metavar=("S", "C"),
                    help="limits (%%) OptCuts' equivalent bound is computed from (default: --stretch, --compress)")
    ap.add_argument("--stretch", type=float, default=3.0)
    ap.add_argument("--compress", type=float, default=3.0)
    ap.add_argument("--timeout", type=float, default=3600.0)
    ap.add_argument("--out")
    ap.add_argument("meshes", nargs="+")
    a = ap.parse_args()
    root = a.out or tempfile.mkdtemp(prefix="darts-bench-")
    rows = []
    meta = {}
    for mesh in a.meshes:
        tag0 = os.path.splitext(os.path.basename(mesh))[0]
        meta[tag0] = (genus(mesh), len(load_obj(mesh)[1]))
        tag = os.path.splitext(os.path.basename(mesh))[0]
        extra = a.flatcut_args.split()
        tools = [("flatcut" + (" " + a.flatcut_args if extra else ""),
                  lambda *args: run_flatcut(*args, extra=extra), a.flatcut)]
        if a.optcuts:
            tools.append(("OptCuts", run_optcuts, a.optcuts))
        for label, run, binary in tools:
            out = os.path.join(root, tag, label)
            shutil.rmtree(out, ignore_errors=True)
            os.makedirs(out)
            s, c = (a.optcuts_limits or (a.stretch, a.compress)) if label == "OptCuts" else (a.stretch, a.compress)
            r = run(binary, os.path.abspath(mesh), out, s, c, a.timeout)
            if "obj" in r:
                r.update(measure(a.bench, r["obj"], a.stretch, a.compress))
            r.update({"mesh": tag, "tool": label, "load": os.getloadavg()[0]})
            print(json.dumps(r), file=sys.stderr, flush=True)
            rows.append(r)
    print(f"\nLimits: stretch {a.stretch} %, compression {a.compress} %, measured by metrics.py's singular values.\n")
    print("| mesh | tool | cuts | cut length mm | dart mouths mm | worst stretch % | worst compression % | faces over | flips | s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "error" in r:
            print(f"| {r['mesh']} | {r['tool']} | – | – | – | – | – | – | – | {r.get('seconds', float('nan')):.1f} ({r['error']}) |")
            continue
        mouths = f"{r['mouths_mm']:.1f}" if "mouths_mm" in r else "–"
        cuts = (f"{r['darts']} darts" if r.get("darts") else "") + \
            (f" {r['seams']} seams ({r['parts']} parts)" if r.get("seams") else "") if "darts" in r else "seams"
        length = r.get("dart_mm", r["cut_mm"])
        print(f"| {r['mesh']} | {r['tool']} | {cuts} | {length:.1f} | {mouths} | {r['stretch_max_pct']:.2f} | "
              f"{r['compress_max_pct']:.2f} | {r['faces_over']} of {r['faces']} | {r['flips']} | {r['seconds']:.1f} |")
    genus_table(rows, meta, a.stretch, a.compress)


def genus_table(rows, meta, stretch, compress):
    """The closed surfaces' table: pieces, seams, the worst stretches measured, faces over, wall
    and CPU time, and the load (1-minute average) when the run ended."""
    print("\n| mesh | genus | faces | limits | tool | pieces | total seam mm | worst stretch % | "
          "worst compr. % | faces over | wall s | CPU s | load |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        g, f = meta[r["mesh"]]
        head = f"| {r['mesh']} | {g} | {f} | ±{stretch:g} / {compress:g} % | {r['tool'].split()[0]} |"
        tail = f" {r.get('seconds', float('nan')):.1f} | {r.get('cpu', float('nan')):.1f} | {r['load']:.1f} |"
        if "error" in r:
            print(head + f" – | – | – | – | – ({r['error'][:90]}) |" + tail)
            continue
        pieces = r["parts"] if r["tool"].startswith("flatcut") else charts(r["obj"][0])
        print(head + f" {pieces} | {r.get('dart_mm', r['cut_mm']):.0f} | {r['stretch_max_pct']:.2f} | {r['compress_max_pct']:.2f} | "
              f"{r['faces_over']} |" + tail)


def charts(path):
    """Connected pieces of an OBJ's UV layout (faces joined by shared texture vertices)."""
    _, F, _, FT = load_obj(path)
    parent = list(range(int(FT.max()) + 1))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for t in FT:
        for k in (1, 2):
            a, b = find(t[0]), find(t[k])
            parent[a] = b
    return len({find(t[0]) for t in FT})


if __name__ == "__main__":
    main()
