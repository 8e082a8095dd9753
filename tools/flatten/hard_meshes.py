#!/usr/bin/env python3
"""Hard flattening inputs for the solver benchmark: disk patches cut from scanned meshes that a
Debian package ships (CGAL's demo data: a camel, a man, mannequin-devil, lion-head), and bench
surfaces remeshed with slivers.

usage: python hard_meshes.py OFF_DIR OUT_DIR

OFF_DIR holds the CGAL meshes (`apt-get download libcgal-demo`, then
`dpkg-deb -x` and untar `usr/share/doc/libcgal-dev/data.tar.gz`: data/meshes/*.off).
Writes OBJ files and prints, per mesh, faces, smallest angle and the disk check.
"""
import os
import sys

import igl
import numpy as np


def write_obj(path, V, F):
    with open(path, "w") as f:
        for v in V:
            f.write("v %.17g %.17g %.17g\n" % tuple(v))
        for t in F:
            f.write("f %d %d %d\n" % tuple(t + 1))


def compact(V, F):
    used = np.unique(F)
    remap = -np.ones(len(V), dtype=np.int64)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def is_disk(V, F):
    """One connected, edge-manifold face set with Euler characteristic 1 and one boundary loop."""
    if len(F) == 0:
        return False
    E = igl.edges(F)
    if len(V) - len(E) + len(F) != 1:
        return False
    if igl.facet_components(F)[0] != 1:
        return False
    # Boundary edges are the edges of one face only; they must all lie on one loop.
    half = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, counts = np.unique(half, axis=0, return_counts=True)
    if counts.max() > 2:
        return False
    return int((counts == 1).sum()) == len(igl.boundary_loop(F))


def bfs_patch(V, F, seed_face, n_faces):
    """Faces reached by breadth-first growth over shared edges from `seed_face`, cut at
    `n_faces`; None unless the result is a disk."""
    TT, _ = igl.triangle_triangle_adjacency(F)
    seen = np.zeros(len(F), dtype=bool)
    order = [seed_face]
    seen[seed_face] = True
    i = 0
    while i < len(order) and len(order) < n_faces:
        for t in TT[order[i]]:
            if t >= 0 and not seen[t]:
                seen[t] = True
                order.append(t)
        i += 1
    Vp, Fp = compact(V, F[np.array(order[:n_faces])])
    return (Vp, Fp) if is_disk(Vp, Fp) else None


def patch_from(V, F, n_faces, rng, tries=200):
    """A disk patch grown from a face with a sliver (smallest angle below 1°) when there is one."""
    ang = np.degrees(igl.internal_angles(V, F).min(1))
    seeds = np.flatnonzero(ang < 1.0)
    if len(seeds) == 0:
        seeds = np.arange(len(F))
    for _ in range(tries):
        p = bfs_patch(V, F, int(rng.choice(seeds)), n_faces)
        if p is not None:
            return p
    raise RuntimeError("no disk patch found")


def slivered(V, F, fraction, rng, t_min=0.008, t_max=0.03):
    """Splits a random `fraction` of interior edges at a point very close to one end (and every
    boundary edge it touches is left alone): each split makes two slivers whose smallest angles
    are a fraction of a degree, on an otherwise well-shaped mesh."""
    F = [list(t) for t in F]
    V = [np.asarray(v, dtype=float) for v in V]
    from collections import defaultdict
    edge_faces = defaultdict(list)
    for t, tri in enumerate(F):
        for k in range(3):
            a, b = tri[(k + 1) % 3], tri[(k + 2) % 3]
            edge_faces[(min(a, b), max(a, b))].append(t)
    interior = sorted(e for e, fs in edge_faces.items() if len(fs) == 2)
    picks = rng.choice(len(interior), size=int(fraction * len(interior)), replace=False)
    touched = set()
    for i in sorted(picks):
        a, b = interior[i]
        ts = edge_faces[(a, b)]
        if any(t in touched for t in ts):
            continue
        s = rng.uniform(t_min, t_max)
        m = len(V)
        V.append((1 - s) * V[a] + s * V[b])
        for t in ts:
            tri = F[t]
            k = [j for j in range(3) if tri[j] != a and tri[j] != b][0]
            c = tri[k]
            # Keep the orientation: replace the triangle (c, x, y) by (c, x, m), (c, m, y).
            x, y = tri[(k + 1) % 3], tri[(k + 2) % 3]
            F[t] = [c, x, m]
            F.append([c, m, y])
            touched.add(t)
            touched.add(len(F) - 1)
    return np.asarray(V), np.asarray(F, dtype=np.int64)


def describe(name, V, F):
    ang = np.degrees(igl.internal_angles(V, F).min(1))
    print("%s faces=%d min_angle=%.3f p1=%.2f disk=%s" % (name, len(F), ang.min(), np.percentile(ang, 1), is_disk(V, F)))


def main():
    off_dir, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(20261125)
    outs = []

    def read(name):
        V, F = igl.read_triangle_mesh(os.path.join(off_dir, name + ".off"))[:2]
        return np.asarray(V, dtype=float), np.asarray(F, dtype=np.int64)

    V, F = read("camel")
    outs.append(("camel_patch_2k", *patch_from(V, F, 2187, rng)))
    V, F = read("man")
    outs.append(("man_patch_10k", *patch_from(V, F, 10000, rng)))
    V, F = read("mannequin-devil")
    outs.append(("mannequin_26k", V, F))
    V, F = read("lion-head")
    outs.append(("lionhead_17k", V, F))
    bench = os.path.join(os.path.dirname(out.rstrip("/")), "meshes")
    for name in ["toe_2k", "saddle_20k"]:
        p = os.path.join(bench, name + ".obj")
        if os.path.exists(p):
            V, F = igl.read_triangle_mesh(p)[:2]
            outs.append((name + "_sliver", *slivered(np.asarray(V), np.asarray(F, dtype=np.int64), 0.15, rng)))
    for name, V, F in outs:
        describe(name, V, F)
        write_obj(os.path.join(out, name + ".obj"), V, F)


if __name__ == "__main__":
    main()
