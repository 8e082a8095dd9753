#!/usr/bin/env python3
"""`flatcut report` on flat pieces whose δ0 is known exactly: time, peak memory and δ0 against the
answer, for one or two builds side by side in one run.

usage: python bench.py --flatcut LABEL=BIN [--flatcut LABEL=BIN]... [--repeat N] [--out DIR]
                       [--only NAME,...]

The pieces (written as OBJ with `v` on the surface and `vt` in the plane, true mm):

  cone-1m       a cone sector (half-angle 50°, slant 20..100 mm, 300° around the axis) unrolled
                exactly: ~1M faces, the unrolled sector spans 230° (not convex). δ0 = 0.
  strip-17k     a hull plank: a band of a cone (half-angle 20°, slant 2000..2300 mm), 1300 mm
                long at mid-width and 300 mm wide, ~17k long faces, unrolled exactly into a
                curved strip (an annular sector, not convex). δ0 = 0.
  cylinder-l    an L-shaped cut of a cylinder (radius 60 mm, 300° of arc, 120 mm high, a quarter
                cut away) unrolled exactly, then stretched by 5 % along the arc: every face has
                σ1 = 1.05, σ2 = 1, so δ0 = ln 1.05 (the straight line across the L's notch
                would make it larger).
  cone-sector   the cone sector at ~20k faces. δ0 = 0.

Every piece lies on rulings: each triangle spans two neighbouring rulings, so the polyhedral
surface is developable exactly and the unrolling (each strip between two rulings laid flat at
the angle between them) is an isometry of it; the only error of the figure is the OBJ's 10
decimals. Each report runs in its own process under /usr/bin/time (wall time and peak memory of
the whole command: reading the OBJ, measuring, writing the JSON), `--repeat` times; the table
gives the median wall and CPU (user + system) times, the largest peak memory, and the machine's
highest one-minute load during the runs (on a shared machine the CPU time is the steadier one). Run it on a quiet machine; it is a benchmark, never a test.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

import numpy as np


def quads(nu, nv, keep=None, reverse=False):
    """Two triangles per kept cell (i, j) of an (nu + 1) × (nv + 1) vertex grid, row-major by j;
    diagonals alternate."""
    tris = []
    for j in range(nv):
        for i in range(nu):
            if keep is not None and not keep(i, j):
                continue
            a, b = j * (nu + 1) + i, j * (nu + 1) + i + 1
            c, d = b + nu + 1, a + nu + 1
            t = [(a, b, c), (a, c, d)] if (i + j) % 2 == 0 else [(a, b, d), (b, c, d)]
            tris += [(x, z, y) for x, y, z in t] if reverse else t
    return np.array(tris, dtype=np.int64)


def compact(V, UV, F):
    """Drops the vertices no triangle uses."""
    used = np.unique(F)
    new = -np.ones(len(V), dtype=np.int64)
    new[used] = np.arange(len(used))
    return V[used], UV[used], new[F]


def cone_band(beta, phi_span, s0, s1, nu, nv):
    """A cone band on rulings (apex at the origin, axis z) and its exact unrolling."""
    phi = np.linspace(0.0, phi_span, nu + 1)
    d = np.c_[math.sin(beta) * np.cos(phi), math.sin(beta) * np.sin(phi), np.full_like(phi, math.cos(beta))]
    step = np.arccos(np.clip((d[1:] * d[:-1]).sum(1), -1.0, 1.0))
    psi = np.r_[0.0, np.cumsum(step)]
    s = np.linspace(s0, s1, nv + 1)
    S, I = np.meshgrid(s, np.arange(nu + 1), indexing="ij")
    V = (S[..., None] * d[I]).reshape(-1, 3)
    UV = np.c_[(S * np.cos(psi[I])).ravel(), (S * np.sin(psi[I])).ravel()]
    # Angle along the rows and slant up the columns turn clockwise in the plane.
    return V, UV, quads(nu, nv, reverse=True), psi[-1]


def cone_sector(faces):
    beta, span = math.radians(50), math.radians(300)
    # Cells about as long as wide at mid-slant: nu / nv ≈ (developed arc at 60 mm) / 80 mm.
    ratio = span * math.sin(beta) * 60.0 / 80.0
    nv = max(2, round(math.sqrt(faces / (2 * ratio))))
    nu = max(2, round(faces / (2 * nv)))
    V, UV, F, dev = cone_band(beta, span, 20.0, 100.0, nu, nv)
    assert dev > math.pi, dev
    return V, UV, F, 0.0


def strip(faces):
    beta, s0, s1 = math.radians(20), 2000.0, 2300.0
    psi_span = 1300.0 / (0.5 * (s0 + s1))
    nv = max(2, round(math.sqrt(faces * 300.0 / 1300.0 / 2)))
    nu = max(2, round(faces / (2 * nv)))
    V, UV, F, _ = cone_band(beta, psi_span / math.sin(beta), s0, s1, nu, nv)
    return V, UV, F, 0.0


def cylinder_l(faces, stretch=1.05):
    r, span, height = 60.0, math.radians(300), 120.0
    nv = max(4, 2 * round(math.sqrt(faces * 4 / 3 * height / (r * span)) / 4))
    nu = max(4, 2 * round(faces * 4 / 3 / (2 * nv) / 2))
    phi = np.linspace(0.0, span, nu + 1)
    chord = 2 * r * math.sin(span / nu / 2)
    z = np.linspace(0.0, height, nv + 1)
    Z, I = np.meshgrid(z, np.arange(nu + 1), indexing="ij")
    V = np.c_[(r * np.cos(phi[I])).ravel(), (r * np.sin(phi[I])).ravel(), Z.ravel()]
    UV = np.c_[(stretch * chord * I).ravel(), Z.ravel()]
    F = quads(nu, nv, keep=lambda i, j: i < nu // 2 or j < nv // 2)
    V, UV, F = compact(V, UV, F)
    return V, UV, F, math.log(stretch)


PIECES = {
    "cone-1m": lambda: cone_sector(1_000_000),
    "strip-17k": lambda: strip(17_000),
    "cylinder-l": lambda: cylinder_l(20_000),
    "cone-sector": lambda: cone_sector(20_000),
}


def write_obj(path, V, UV, F):
    with open(path, "w") as f:
        np.savetxt(f, V, fmt="v %.10f %.10f %.10f")
        np.savetxt(f, UV, fmt="vt %.10f %.10f")
        G = F + 1
        np.savetxt(f, np.c_[G[:, 0], G[:, 0], G[:, 1], G[:, 1], G[:, 2], G[:, 2]],
                   fmt="f %d/%d %d/%d %d/%d")


def load():
    return os.getloadavg()[0]


def timed(cmd):
    """Runs `cmd` under /usr/bin/time; returns (wall s, CPU s, peak MB, exit code)."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        p = subprocess.run(["/usr/bin/time", "-f", "%e %U %S %M", "-o", tf.name] + cmd,
                           capture_output=True, text=True)
        if p.returncode not in (0, 3):
            sys.stderr.write(p.stderr[-2000:])
        wall, user, system, kb = open(tf.name).read().split()[-4:]
    return float(wall), float(user) + float(system), int(kb) / 1024.0, p.returncode


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--flatcut", action="append", required=True, help="LABEL=BIN of flatcut")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=tempfile.mkdtemp(prefix="flatcut-report-bench-"))
    ap.add_argument("--only", help="comma-separated piece names")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    tools = [f.split("=", 1) for f in a.flatcut]
    names = a.only.split(",") if a.only else list(PIECES)
    head = "| piece | faces | exact δ0 |"
    rule = "|---|---|---|"
    for label, _ in tools:
        head += f" δ0 {label} | report s {label} | CPU s {label} | peak MB {label} |"
        rule += "---|---|---|---|"
    print(head + " load |")
    print(rule + "---|")
    for name in names:
        V, UV, F, exact = PIECES[name]()
        obj = os.path.join(a.out, f"{name}.obj")
        write_obj(obj, V, UV, F)
        row = f"| {name} | {len(F)} | {exact:.6f} |"
        loads = [load()]
        for label, binary in tools:
            times, cpus, peaks = [], [], []
            d0 = float("nan")
            for k in range(a.repeat):
                js = os.path.join(a.out, f"{name}.{label}.json")
                wall, cpu, mb, code = timed([binary, "report", obj, "--json", js])
                times.append(wall)
                cpus.append(cpu)
                peaks.append(mb)
                if code in (0, 3):
                    d0 = json.load(open(js))["delta0"]
            loads.append(load())
            d0s = "∞" if d0 is None else f"{d0:.6f}"
            row += (f" {d0s} | {statistics.median(times):.2f} | {statistics.median(cpus):.2f} |"
                    f" {max(peaks):.0f} |")
        print(row + f" {max(loads):.1f} |", flush=True)


if __name__ == "__main__":
    main()
