#!/usr/bin/env python3
"""Cross-checks `flatcut report` against the shared benchmark scorer (shared/bench/metrics.py).

usage: compare_metrics.py FLAT.obj REPORT.json [--piece NAME] [--tol 1e-6]

FLAT.obj is a flattened piece as `flatcut flatten` writes it (`v`, one `vt` per vertex in true mm,
`f a/a b/b c/c`); REPORT.json is flatcut's report (one object, or an array for several pieces: the
entry is picked by --piece, else by the OBJ's file name, else by face count). Both scorers see the
same triangles and the measures that do not depend on scale must agree:

  * conformal distortion: metrics' area-weighted mean of log(s1/s2) = δ1_mean / 2, since Duncan's
    δ1 = log(μ1/μ2) = 2 log(σ1/σ2). Uniform scaling leaves the ratio alone, so metrics' area
    normalisation does not matter. Only comparable when nothing is flipped: flatcut scores a
    flipped face as infinitely distorted (δ1 = ∞, JSON null), metrics.py scores it with |s2|.
  * flips: metrics' n_flipped = flatcut's `flipped` (metrics counts against each chart's majority
    orientation, flatcut against counter-clockwise; the same for a CCW piece without collapsed
    triangles).
  * boundary length: flatcut measures the layout as drawn (true mm); metrics first scales the
    layout by k = sqrt(A3 / Σ|A2|) so that the areas match. Every boundary edge scales by k, so
    1 + bnd_metrics = k (1 + bnd_flatcut), i.e. bnd_metrics = k (1 + bnd_flatcut) − 1. k itself
    must equal sqrt(area_3d_mm2 / area_2d_mm2) from the JSON (flatcut's 2D area is signed; the
    same as Σ|A2| without flips).

The JSON must be computed from this very OBJ (`flatcut report FLAT.obj --json R.json`) for a 1e-6
agreement: `flatcut flatten --report` measures the layout before the OBJ rounds it to 6 decimals,
which moves small measures by more than 1e-6 relative (the table still shows how much).

Exits 0 when every compared row agrees within --tol relative, 1 on disagreement, 2 on bad input.
Measures that depend on scale (δ2 vs metrics' symmetric Dirichlet, area) are printed for reference
and not compared.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "..", "shared", "bench"))
from metrics import distortion_metrics  # noqa: E402

# Differences below this are round-off of sums over ~10⁵ terms near zero, not disagreement.
ABS_FLOOR = 1e-12


def read_flat_obj(path):
    """`v`, `vt` and `f` (corner indices v/vt, polygons fan-triangulated), like the bench readers."""
    V, UV, F, FUV = [], [], [], []
    with open(path) as f:
        for line in f:
            tok = line.split()
            if not tok:
                continue
            if tok[0] == "v":
                V.append([float(x) for x in tok[1:4]])
            elif tok[0] == "vt":
                UV.append([float(x) for x in tok[1:3]])
            elif tok[0] == "f":
                vi, ti = [], []
                for c in tok[1:]:
                    parts = c.split("/")
                    v = int(parts[0])
                    vi.append(v - 1 if v > 0 else len(V) + v)
                    if len(parts) < 2 or not parts[1]:
                        raise ValueError(f"{path}: face without vt ({line.strip()}): not a flattened OBJ")
                    t = int(parts[1])
                    ti.append(t - 1 if t > 0 else len(UV) + t)
                for k in range(1, len(vi) - 1):
                    F.append([vi[0], vi[k], vi[k + 1]])
                    FUV.append([ti[0], ti[k], ti[k + 1]])
    if not F:
        raise ValueError(f"{path}: no faces")
    return (np.array(V, dtype=np.float64), np.array(F, dtype=np.int64),
            np.array(UV, dtype=np.float64), np.array(FUV, dtype=np.int64))


def pick_report(data, obj_path, n_faces, piece):
    if isinstance(data, dict):
        return data
    if piece is not None:
        hits = [r for r in data if r.get("name") == piece]
        if not hits:
            raise ValueError(f"no piece named '{piece}' in the report; it has {[r.get('name') for r in data]}")
        return hits[0]
    stem = os.path.splitext(os.path.basename(obj_path))[0]
    same = [r for r in data if r.get("faces") == n_faces]
    exact = [r for r in same if r.get("name") == stem]
    if len(exact) == 1:
        return exact[0]
    by_name = [r for r in same if r.get("name") and (r["name"] in stem or stem in r["name"])]
    if len(by_name) == 1:
        return by_name[0]
    if len(same) == 1:
        return same[0]
    raise ValueError(f"cannot tell which of {[r.get('name') for r in data]} is {obj_path}: use --piece")


def num(x):
    """JSON null (serde's ∞/NaN) → inf."""
    return math.inf if x is None else float(x)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("obj")
    ap.add_argument("json")
    ap.add_argument("--piece", help="name of the piece in a report array")
    ap.add_argument("--tol", type=float, default=1e-6, help="relative tolerance (default 1e-6)")
    a = ap.parse_args()
    try:
        V, F, UV, FUV = read_flat_obj(a.obj)
        with open(a.json) as f:
            rep = pick_report(json.load(f), a.obj, len(F), a.piece)
    except (OSError, ValueError) as e:
        print(e, file=sys.stderr)
        return 2
    if rep.get("faces") != len(F):
        print(f"{a.obj} has {len(F)} faces, the report '{rep.get('name')}' {rep.get('faces')}", file=sys.stderr)
        return 2
    m = distortion_metrics(V, F, UV, FUV)
    if "error" in m:
        print(f"metrics.py: {m['error']}", file=sys.stderr)
        return 2

    k = m["uv_scale_applied"]
    rows = []  # (quantity, metrics.py, flatcut-derived, compared?)
    flipped = int(rep["flipped"])
    rows.append(("flipped faces", m["n_flipped"], flipped, True))
    if flipped == 0:
        rows.append(("conformal mean log(s1/s2) = δ1_mean/2", m["conf_mean"], num(rep["delta1_mean"]) / 2, True))
        rows.append(("conformal max  log(s1/s2) = δ1_max/2", m["conf_max"], num(rep["delta1_max"]) / 2, True))
        rows.append(("area scale k = sqrt(A3/A2)", k, math.sqrt(rep["area_3d_mm2"] / rep["area_2d_mm2"]), True))
    else:
        print(f"{flipped} flipped faces: flatcut's δ1 is ∞ there, conformal means not comparable")
    bnd_ours = rep["boundary_length_error"]
    rows.append(("boundary error (k(1+ours)-1)", m.get("bnd_len_rel_err", 0.0), k * (1 + bnd_ours) - 1, True))
    rows.append(("boundary error, ours as drawn", None, bnd_ours, False))
    rows.append(("symmetric Dirichlet / δ2 (scale-dependent)", m["symd_mean"], num(rep["delta2_mean"]), False))
    rows.append(("area |log s1 s2| (scale-dependent)", m["area_mean"], num(rep["area_log_mean"]), False))

    print(f"{a.obj} vs '{rep.get('name')}' ({len(F)} faces, metrics' UV scale k = {k:.9f})")
    print(f"{'quantity':46s} {'metrics.py':>17s} {'flatcut':>17s} {'rel. diff':>10s}")
    bad = 0
    for name, theirs, ours, compared in rows:
        if theirs is None:
            print(f"{name:46s} {'':>17s} {ours:17.10g} {'':>10s}")
            continue
        diff = abs(theirs - ours)
        scale = max(abs(theirs), abs(ours))
        rel = diff / scale if scale > 0 else 0.0
        ok = diff <= a.tol * scale + ABS_FLOOR
        mark = ("ok" if ok else "DIFFERS") if compared else "(info)"
        if compared and not ok:
            bad += 1
        print(f"{name:46s} {theirs:17.10g} {ours:17.10g} {rel:10.2e} {mark}")
    if bad:
        print(f"{bad} quantities disagree beyond {a.tol:g} relative")
        return 1
    print(f"all compared quantities agree within {a.tol:g} relative")
    return 0


if __name__ == "__main__":
    sys.exit(main())
