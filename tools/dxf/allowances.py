#!/usr/bin/env python3
"""Measures a pattern DXF's allowances with ezdxf, as an AAMA importer reads the file.

Usage: allowances.py FILE.dxf [--tolerance MM] [--table]

For every piece (a BLOCK placed by an INSERT) it reads the piece text (`Piece Name:`, `Size:`,
`Quantity:`, `Material:` on layer 1), the cut line (layer 1), the sew line (layer 14, its arcs
flattened by ezdxf's own path tools) and the edge annotations (layer-15 TEXT
`name: kind W mm`, written at the middle of each run of one allowance). Around each annotation
it walks the sew line both ways while the distance from the sew line to the cut line stays what
it is there: that stretch is the edge, and its measured allowance is the distance from the sew
line to the cut line along it (1 mm kept clear of its ends, where the corners are).

Prints one JSON object (blocks, layers, each edge's stated and measured allowance — least, mean
and largest — and length, and the share of the sew line the edges found cover: near a corner
the distance to the cut line is the corner's, not an edge's); with --table a Markdown table
instead. Exit 1 when a block lacks its piece text or an edge's mean allowance differs from its
annotation by more than the tolerance (0.02 mm by default: the sew line's arcs are exact, the
cut line is offset from their chords), or its least or largest by more than five times that (a
sew point at a concave kink is a little farther from the joined cut lines).
"""
import json
import math
import re
import sys

import numpy as np
import ezdxf
from scipy.spatial import cKDTree
from ezdxf import path as ezpath
from ezdxf import recover

PIECE_TEXT = ["Piece Name:", "Size:", "Quantity:", "Material:"]
NOTE = re.compile(r"^(?:(?P<name>.*): )?(?P<kind>seam|hem|fold|lasting|raw) (?P<mm>[0-9.]+) mm$")
STEP_MM = 0.25  # sampling step along the sew line
SAME_MM = 0.1  # a run of one allowance: the distance stays within this of its middle's
CLEAR_MM = 1.0  # kept clear of a run's ends


def points(entity, tol=0.005):
    """World-coordinate points of a (virtual) polyline, arcs flattened."""
    p = ezpath.make_path(entity)
    return np.array([[v.x, v.y] for v in p.flattening(tol)])


def resample(closed_pts, step):
    """Points every `step` mm along a closed polyline (and their arc length)."""
    p = np.vstack([closed_pts, closed_pts[:1]])
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    total = s[-1]
    t = np.arange(0.0, total, step)
    x = np.interp(t, s, p[:, 0])
    y = np.interp(t, s, p[:, 1])
    return np.stack([x, y], axis=1), total


def dist_to_polyline(q, closed_pts):
    """Distance from each point of q to the closed polyline: to its points every 0.02 mm (a
    k-d tree), which is within 1e-5 mm of the distance to the line at these allowances."""
    dense, _ = resample(closed_pts, 0.02)
    dense = np.vstack([dense, closed_pts])
    d, _ = cKDTree(dense).query(q)
    return d


def measure(block_entities):
    cut = sew = None
    notes, texts = [], []
    for e in block_entities:
        layer, t = e.dxf.layer, e.dxftype()
        if t == "POLYLINE" and e.is_closed and layer == "1":
            cut = points(e)
        elif t == "POLYLINE" and e.is_closed and layer == "14":
            sew = points(e)
        elif t == "TEXT" and layer == "1":
            texts.append(e.dxf.text)
        elif t == "TEXT" and layer == "15":
            m = NOTE.match(e.dxf.text)
            if m:
                notes.append((e.dxf.insert.x, e.dxf.insert.y, m))
    return cut, sew, notes, texts


def edges_of(cut, sew, notes):
    q, total = resample(sew, STEP_MM)
    d = dist_to_polyline(q, cut)
    n = len(q)
    out = []
    covered = np.zeros(n, dtype=bool)
    for x, y, m in notes:
        mid = int(np.argmin(np.linalg.norm(q - np.array([x, y]), axis=1)))
        ref = d[mid]
        lo = hi = mid
        while (hi - mid) < n and abs(d[(hi + 1) % n] - ref) <= SAME_MM:
            hi += 1
        while (mid - lo) < n and abs(d[(lo - 1) % n] - ref) <= SAME_MM:
            lo -= 1
        idx = [(k % n) for k in range(lo, hi + 1)]
        covered[idx] = True
        clear = int(round(CLEAR_MM / STEP_MM))
        inner = idx[clear:len(idx) - clear] or idx
        dv = d[inner]
        out.append({
            "edge": m.group("name") or "(default seam)",
            "kind": m.group("kind"),
            "stated_mm": float(m.group("mm")),
            "measured_mm": [round(float(dv.min()), 4), round(float(dv.mean()), 4), round(float(dv.max()), 4)],
            "length_mm": round(len(idx) * STEP_MM, 1),
        })
    return out, float(covered.mean()), total


def main():
    args = sys.argv[1:]
    if not args:
        print("usage: allowances.py FILE.dxf [--tolerance MM] [--table]", file=sys.stderr)
        sys.exit(2)
    tol = float(args[args.index("--tolerance") + 1]) if "--tolerance" in args else 0.02
    doc, auditor = recover.readfile(args[0])
    msp = doc.modelspace()
    out = {"ezdxf": ezdxf.__version__, "dxfversion": doc.dxfversion,
           "layers": sorted(l.dxf.name for l in doc.layers), "blocks": [], "problems": []}
    problems = out["problems"]
    for ins in msp.query("INSERT"):
        blk = doc.blocks.get(ins.dxf.name)
        if blk is None:
            problems.append(f"INSERT of missing block {ins.dxf.name}")
            continue
        cut, sew, notes, texts = measure(list(ins.virtual_entities()))
        b = {"block": blk.name, "texts": texts, "edges": []}
        for key in PIECE_TEXT:
            if not any(t.startswith(key) for t in texts):
                problems.append(f"block {blk.name}: no `{key}` TEXT on layer 1")
        if cut is None or sew is None:
            problems.append(f"block {blk.name}: no closed cut line (1) or sew line (14)")
            out["blocks"].append(b)
            continue
        b["edges"], b["covered"], b["sew_length_mm"] = edges_of(cut, sew, notes)
        for e in b["edges"]:
            lo, mean, hi = e["measured_mm"]
            off = max(abs(lo - e["stated_mm"]), abs(hi - e["stated_mm"]))
            if abs(mean - e["stated_mm"]) > tol or off > 5 * tol:
                problems.append(f"block {blk.name}: edge {e['edge']} states {e['stated_mm']} mm, measured {lo} / {mean} / {hi} mm")
        out["blocks"].append(b)
    if "--table" in args:
        print("| block | edge | kind | stated mm | measured mm (min / mean / max) | length mm |")
        print("|---|---|---|---|---|---|")
        for b in out["blocks"]:
            for e in b["edges"]:
                lo, mean, hi = e["measured_mm"]
                print(f"| {b['block']} | {e['edge']} | {e['kind']} | {e['stated_mm']:.1f} | {lo:.3f} / {mean:.3f} / {hi:.3f} | {e['length_mm']:.1f} |")
        for p in problems:
            print(f"problem: {p}")
    else:
        print(json.dumps(out))
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
