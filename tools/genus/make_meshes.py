#!/usr/bin/env python3
"""Closed test surfaces of several genera for `--split auto` and its comparison with OptCuts,
written as OBJ in millimetres with a manifest (source, licence, genus, faces) beside them.

usage: python make_meshes.py OFF_DIR OUT_DIR [SCANS_DIR]

OFF_DIR holds the meshes of Debian's `libcgal-demo` package (`apt-get download libcgal-demo`,
`dpkg-deb -x` it, untar `usr/share/doc/libcgal-dev/data.tar.gz`: `data/meshes/*.off`; CGAL's
demo data, distributed by Debian under the terms in the package's copyright file). Each is scaled
so its largest extent is the size given below. Generated here (no licence needed, this script's):
a torus and a genus-12 "boot": a curved strap 5 mm thick with two rows of six eyelet holes,
closed all round (an upper's eyelet facing cut to its outline), its strip subdivided to
about 10k triangles.

SCANS_DIR (optional) is a checkout of github.com/alecjacobson/common-3d-test-models (its commit
below): the closed scans of about 100k faces taken from it for the closed-scan benchmark. Its
README gives each model's source; it states no licence of its own for them, so the manifest
names the source it gives. The meshes are not copied into this repository. The Igea scan
(268,686 faces as distributed) is decimated to 100,000 by quadric error with the
`fast-simplification` package (pip; MIT), deterministic: only this script needs it.
"""
import json
import math
import os
import sys

import numpy as np

# name in the CGAL data, extent in mm, what it stands for
CGAL = [
    ("bear", 300, "stuffed toy with limbs (teddy bear), genus 0"),
    ("bull", 300, "animal with legs and horns, genus 0"),
    ("elephant", 300, "elephant, trunk joined to the body: genus 3"),
    ("knot1", 300, "trefoil knot tube, genus 1"),
    ("eight", 200, "figure eight, genus 2"),
    ("bunny00", 200, "Stanford bunny, closed scan, genus 0"),
    ("sphere", 200, "sphere (a ball), genus 0"),
    ("refined_elephant", 300, "elephant, refined closed scan (88,928 faces), trunk joined: genus 3"),
]

# common-3d-test-models: the commit read, and the scans taken from it: name, extent in mm, what
# it stands for, the source its README gives. (ogre.obj, 124,008 faces, is open: 236 boundary
# edges.)
SCANS_COMMIT = "8a4f864"
SCANS = [
    ("nefertiti", 480, "bust of Nefertiti, closed scan (99,938 faces), genus 0",
     "Berlin Egyptian Museum scan via thingiverse.com/thing:3974391"),
]
# Scans distributed as PLY triangle strips, decimated to a face count: name, extent in mm, faces,
# what it stands for, source. (horse.zip's PLY, 96,966 faces, passes through itself: refused.)
STRIP_SCANS = [
    ("igea", 300, 100_000, "Igea head, closed scan decimated to 100,000 faces, genus 0", "Cyberware"),
]


def read_obj(path):
    V, F = [], []
    for ln in open(path):
        if ln.startswith("v "):
            V.append(list(map(float, ln.split()[1:4])))
        elif ln.startswith("f "):
            F.append([int(t.split("/")[0]) - 1 for t in ln.split()[1:4]])
    return np.array(V), np.array(F)


def read_off(path):
    lines = [ln for ln in open(path).read().splitlines() if ln.strip() and not ln.startswith("#")]
    head = lines[0].split()
    if len(head) == 1:
        nv, nf = map(int, lines[1].split()[:2])
        s = 2
    else:
        nv, nf = int(head[1]), int(head[2])
        s = 1
    V = np.array([list(map(float, ln.split()[:3])) for ln in lines[s:s + nv]])
    F = np.array([list(map(int, ln.split()[1:4])) for ln in lines[s + nv:s + nv + nf]])
    return V, F


def read_ply_strips(path):
    """A binary little-endian PLY of float x y z vertices and one `tristrips` element (strips
    separated by -1, alternate triangles reversed to keep one orientation), as triangles."""
    data = open(path, "rb").read()
    head_end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:head_end].decode("ascii").split("\n")
    assert "format binary_little_endian 1.0" in head and "element tristrips 1" in head, path
    nv = int(next(ln for ln in head if ln.startswith("element vertex")).split()[2])
    V = np.frombuffer(data, "<f4", nv * 3, head_end).reshape(nv, 3).astype(float)
    at = head_end + 12 * nv
    n = int(np.frombuffer(data, "<i4", 1, at)[0])
    strips = np.frombuffer(data, "<i4", n, at + 4)
    F = []
    for strip in np.split(strips, np.flatnonzero(strips < 0)):
        strip = strip[strip >= 0]
        for k in range(len(strip) - 2):
            a, b, c = strip[k], strip[k + 1], strip[k + 2]
            if len({a, b, c}) == 3:
                F.append((a, b, c) if k % 2 == 0 else (b, a, c))
    return V, np.array(F)


def decimated(V, F, faces):
    """The mesh decimated to `faces` triangles by quadric error (fast-simplification)."""
    import fast_simplification

    V2, F2 = fast_simplification.simplify(V.astype(np.float32), F.astype(np.int32),
                                          target_reduction=1 - faces / len(F))
    return np.asarray(V2, float), np.asarray(F2, int)


def write_obj(path, V, F):
    with open(path, "w") as f:
        for v in V:
            f.write("v %.9g %.9g %.9g\n" % tuple(v))
        for t in F:
            f.write("f %d %d %d\n" % tuple(t + 1))


def genus(F):
    E = set()
    for t in F:
        for k in range(3):
            a, b = t[k], t[(k + 1) % 3]
            E.add((min(a, b), max(a, b)))
    chi = len(np.unique(F)) - len(E) + len(F)
    return (2 - chi) // 2


def torus(R=80.0, r=30.0, n=96, m=40):
    V, F = [], []
    for i in range(n):
        for j in range(m):
            u, v = 2 * math.pi * i / n, 2 * math.pi * j / m
            V.append([(R + r * math.cos(v)) * math.cos(u), (R + r * math.cos(v)) * math.sin(u), r * math.sin(v)])
    idx = lambda i, j: (i % n) * m + j % m  # noqa: E731
    for i in range(n):
        for j in range(m):
            F.append([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)])
            F.append([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)])
    return np.array(V), np.array(F)


def boot(holes_per_row=6, sub=4, cell=10.0, thick=5.0, bend_radius=60.0):
    """A strap of (3·holes + 1) × 5 cells with holes at cells (3k + 1, 1) and (3k + 1, 3),
    each cell cut into sub × sub quads, closed by walls, bent round a cylinder."""
    nx, ny = 3 * holes_per_row + 1, 5
    hole = lambda i, j: j in (1, 3) and i % 3 == 1  # noqa: E731
    N, M = nx * sub, ny * sub
    V, F = [], []
    ids = {}

    def vid(i, j, top):
        k = (i, j, top)
        if k not in ids:
            ids[k] = len(V)
            V.append([i * cell / sub, j * cell / sub, thick if top else 0.0])
        return ids[k]

    def quad(a, b, c, d):
        F.append([a, b, c])
        F.append([a, c, d])

    solid = lambda I, J: 0 <= I < N and 0 <= J < M and not hole(I // sub, J // sub)  # noqa: E731
    for J in range(M):
        for I in range(N):
            if not solid(I, J):
                continue
            quad(vid(I, J, True), vid(I + 1, J, True), vid(I + 1, J + 1, True), vid(I, J + 1, True))
            quad(vid(I, J, False), vid(I, J + 1, False), vid(I + 1, J + 1, False), vid(I + 1, J, False))
            for (a, b), (c, d), nb in [((I, J), (I + 1, J), solid(I, J - 1)),
                                       ((I + 1, J), (I + 1, J + 1), solid(I + 1, J)),
                                       ((I + 1, J + 1), (I, J + 1), solid(I, J + 1)),
                                       ((I, J + 1), (I, J), solid(I - 1, J))]:
                if not nb:
                    quad(vid(a, b, False), vid(c, d, False), vid(c, d, True), vid(a, b, True))
    V = np.array(V)
    # Bend round the cylinder of axis y: x becomes an arc, z the distance from the axis.
    theta = (V[:, 0] - V[:, 0].mean()) / bend_radius
    rad = bend_radius + V[:, 2]
    B = np.stack([rad * np.sin(theta), V[:, 1] * 1.0, rad * np.cos(theta)], axis=1)
    return B, np.array(F)


def write_scan(out, name, size, V, F, what, source):
    """Writes a common-3d-test-models scan scaled to `size` mm; returns its manifest entry."""
    V = (V - V.min(0)) * (size / np.ptp(V, axis=0).max())
    write_obj(os.path.join(out, name + ".obj"), V, F)
    return {"file": name + ".obj", "what": what, "faces": len(F), "genus": int(genus(F)),
            "source": f"github.com/alecjacobson/common-3d-test-models {SCANS_COMMIT} {source}",
            "licence": "none stated in that repository; see the source", "scaled_to_mm": size}


def main():
    off_dir, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    manifest = []
    for name, size, what in CGAL:
        V, F = read_off(os.path.join(off_dir, name + ".off"))
        V = (V - V.min(0)) * (size / np.ptp(V, axis=0).max())
        write_obj(os.path.join(out, name + ".obj"), V, F)
        manifest.append({"file": name + ".obj", "what": what, "faces": len(F), "genus": int(genus(F)),
                         "source": f"Debian libcgal-demo, data/meshes/{name}.off (CGAL demo data)",
                         "licence": "as in Debian's libcgal-demo copyright file", "scaled_to_mm": size})
    for name, (V, F), what in [("torus", torus(), "torus R 80 mm r 30 mm, genus 1"),
                                ("boot12", boot(), "curved eyelet strap with 12 eyelets, genus 12")]:
        write_obj(os.path.join(out, name + ".obj"), V, F)
        manifest.append({"file": name + ".obj", "what": what, "faces": len(F), "genus": int(genus(F)),
                         "source": "generated by tools/genus/make_meshes.py", "licence": "this project's"})
    if len(sys.argv) > 3:
        for name, size, what, source in SCANS:
            V, F = read_obj(os.path.join(sys.argv[3], "data", name + ".obj"))
            manifest.append(write_scan(out, name, size, V, F, what, f"data/{name}.obj: {source}"))
        for name, size, faces, what, source in STRIP_SCANS:
            V, F = decimated(*read_ply_strips(os.path.join(sys.argv[3], "data", name + ".ply")), faces)
            manifest.append(write_scan(out, name, size, V, F, what,
                                       f"data/{name}.ply: {source}, decimated by fast-simplification"))
    json.dump(manifest, open(os.path.join(out, "manifest.json"), "w"), indent=1)
    for m in manifest:
        print(m["file"], m["faces"], "faces, genus", m["genus"])


if __name__ == "__main__":
    main()
