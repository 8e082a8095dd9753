#!/usr/bin/env python3
"""Benchmark of the mirrored split (`flatten --split auto --symmetry auto`) on a plush-like body.

The body: an ellipsoid (semi-axes 70, 50, 90 mm) with two ears symmetric across x = 0, over an
icosphere whose directions are turned (0.41 rad about (0.3, 0.7, 0.2)) so that its triangles are
symmetric about no plane: the same shape as tests/genus.rs builds. For each subdivision level it
runs the split with and without symmetry, in the same run, and prints faces, parts and seconds.
`--freq N` builds the body over a geodesic sphere of frequency N instead (each icosahedron face
cut into N² triangles: 20 N² faces, so N = 26 gives the 13,520 faces of the stuffed-toy class);
`--write FILE` only writes that body as OBJ.

    python3 tools/symmetry/plush_bench.py [--flatcut target/release/flatcut] [--levels 3 4 5]
        [--freq 26] [--pct 8] [--write plush.obj]
"""

import argparse
import math
import os
import subprocess
import tempfile
import time


def icosphere(levels):
    t = (1.0 + math.sqrt(5.0)) / 2.0
    raw = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
           (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    p = [normalize(v) for v in raw]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        mid = {}
        nxt = []

        def m(x, y):
            k = (min(x, y), max(x, y))
            if k not in mid:
                p.append(normalize(tuple(a + b for a, b in zip(p[x], p[y]))))
                mid[k] = len(p) - 1
            return mid[k]

        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nxt += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nxt
    return p, f


def geodesic(freq):
    """The icosahedron with each face cut into freq² triangles, its points pushed out to the
    unit sphere; points on a shared edge or corner made once."""
    p0, f0 = icosphere(0)
    p, f, index = [], [], {}

    def point(a, b, c, i, j):
        # Barycentric (freq - i - j, i, j) of face (a, b, c), keyed by its exact weights on the
        # corners so that faces sharing an edge share its points.
        w = {a: freq - i - j, b: i, c: j}
        key = tuple(sorted((v, k) for v, k in w.items() if k))
        if key not in index:
            q = [sum(p0[v][d] * k for v, k in key) for d in range(3)]
            p.append(normalize(q))
            index[key] = len(p) - 1
        return index[key]

    for a, b, c in f0:
        for j in range(freq):
            for i in range(freq - j):
                u, v, w = point(a, b, c, i, j), point(a, b, c, i + 1, j), point(a, b, c, i, j + 1)
                f.append((u, v, w))
                if i + j + 1 < freq:
                    f.append((v, point(a, b, c, i + 1, j + 1), w))
    return p, f


def normalize(v):
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v)


def turn(v, axis, angle):
    k = normalize(axis)
    c, s = math.cos(angle), math.sin(angle)
    dot = sum(a * b for a, b in zip(k, v))
    cross = (k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0])
    return tuple(v[i] * c + cross[i] * s + k[i] * dot * (1 - c) for i in range(3))


def plush_obj(levels=None, freq=None):
    ears = [normalize((0.55, 0.25, 0.8)), normalize((-0.55, 0.25, 0.8))]
    p, f = geodesic(freq) if freq else icosphere(levels)
    out = []
    for v in p:
        d = normalize(turn(v, (0.3, 0.7, 0.2), 0.41))
        e = 1.0 / math.sqrt((d[0] / 70) ** 2 + (d[1] / 50) ** 2 + (d[2] / 90) ** 2)
        bump = sum(0.35 * math.exp(-sum((a - b) ** 2 for a, b in zip(d, c)) / 0.12) for c in ears)
        r = e * (1 + bump)
        out.append("v %.9f %.9f %.9f" % tuple(x * r for x in d))
    out += ["f %d %d %d" % (a + 1, b + 1, c + 1) for a, b, c in f]
    return "\n".join(out) + "\n", len(f)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--flatcut", default="target/release/flatcut")
    ap.add_argument("--levels", type=int, nargs="+", default=[3, 4])
    ap.add_argument("--freq", type=int, nargs="+", default=[])
    ap.add_argument("--pct", default="8")
    ap.add_argument("--write")
    a = ap.parse_args()
    bodies = [("f%d" % n, {"freq": n}) for n in a.freq] or [("%d" % lv, {"levels": lv})
                                                            for lv in a.levels]
    if a.write:
        text, faces = plush_obj(**bodies[0][1])
        with open(a.write, "w") as fh:
            fh.write(text)
        print(a.write, faces, "faces")
        return
    print("| faces | symmetry | parts | seconds |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        for lv, how in bodies:
            text, faces = plush_obj(**how)
            src = os.path.join(d, "plush%s.obj" % lv)
            with open(src, "w") as fh:
                fh.write(text)
            for sym in ["auto", "off"]:
                out = os.path.join(d, "%s-%s" % (lv, sym))
                os.mkdir(out)
                t0 = time.time()
                r = subprocess.run([a.flatcut, "flatten", src, "-o", os.path.join(out, "f.obj"),
                                    "--max-stretch", a.pct, "--max-compress", a.pct,
                                    "--split", "auto", "--symmetry", sym],
                                   capture_output=True, text=True)
                dt = time.time() - t0
                parts = len([n for n in os.listdir(out) if n.endswith(".obj")])
                status = "" if r.returncode == 0 else " (exit %d)" % r.returncode
                print("| %d | %s | %d%s | %.1f |" % (faces, sym, parts, status, dt))


if __name__ == "__main__":
    main()
