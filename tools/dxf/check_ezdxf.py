#!/usr/bin/env python3
"""Checks a flatcut DXF with ezdxf, an independent reader: audit, AAMA structure, geometry.

Usage: check_ezdxf.py FILE.dxf [--resave OUT.dxf] [--aama]

Prints one JSON object: ezdxf's audit figures, the layers, blocks and inserts, and every
polyline, line and point as ezdxf sees it in world coordinates (inserts resolved by ezdxf), so
the caller can compare geometry. With --aama the AAMA/ASTM D6673 structure is checked (one
block per piece on INSERT, layer-1 boundary and piece text, at most one grain LINE on 7).
With --resave the document is written again by ezdxf's own writer. Exit 1 on any failure.
"""
import json
import sys

import ezdxf
from ezdxf import recover

AAMA_LAYERS = ["1", "2", "3", "4", "6", "7", "8", "11", "13", "14", "15"]
PIECE_TEXT = ["Piece Name:", "Size:", "Quantity:", "Material:"]


def fail(msg):
    print(json.dumps({"error": msg}))
    sys.exit(1)


def points_of(e):
    t = e.dxftype()
    if t == "POLYLINE":
        return [[v.dxf.location.x, v.dxf.location.y] for v in e.vertices], bool(e.is_closed)
    if t == "LINE":
        return [[e.dxf.start.x, e.dxf.start.y], [e.dxf.end.x, e.dxf.end.y]], False
    if t == "POINT":
        return [[e.dxf.location.x, e.dxf.location.y]], False
    return None, False


def main():
    args = sys.argv[1:]
    if not args:
        fail("usage: check_ezdxf.py FILE.dxf [--resave OUT.dxf] [--aama]")
    path = args[0]
    doc, auditor = recover.readfile(path)
    audit = doc.audit()
    out = {
        "ezdxf": ezdxf.__version__,
        "dxfversion": doc.dxfversion,
        "recover_errors": len(auditor.errors),
        "audit_errors": len(audit.errors),
        "audit_fixes": len(audit.fixes),
        "audit_messages": [str(m.message) for m in list(audit.errors) + list(auditor.errors)],
        "layers": sorted(l.dxf.name for l in doc.layers),
        "blocks": [],
        "entities": [],
    }
    msp = doc.modelspace()
    inserts = msp.query("INSERT")
    out["inserts"] = len(inserts)
    problems = []
    for ins in inserts:
        blk = doc.blocks.get(ins.dxf.name)
        if blk is None:
            problems.append(f"INSERT of missing block {ins.dxf.name}")
            continue
        texts = [t.dxf.text for t in blk.query("TEXT") if t.dxf.layer == "1"]
        boundary = [p for p in blk.query("POLYLINE") if p.dxf.layer == "1" and p.is_closed]
        grain = [l for l in blk.query("LINE") if l.dxf.layer == "7"]
        out["blocks"].append({"name": blk.name, "texts": texts, "boundaries": len(boundary), "grain_lines": len(grain)})
        for e in ins.virtual_entities():
            pts, closed = points_of(e)
            if pts is not None:
                out["entities"].append({"block": blk.name, "layer": e.dxf.layer, "type": e.dxftype(), "closed": closed, "points": pts})
    for e in msp:
        if e.dxftype() == "INSERT":
            continue
        pts, closed = points_of(e)
        if pts is not None:
            out["entities"].append({"block": None, "layer": e.dxf.layer, "type": e.dxftype(), "closed": closed, "points": pts})
    if "--aama" in args:
        if doc.dxfversion != "AC1009":
            problems.append(f"version {doc.dxfversion}, expected AC1009 (R12)")
        missing = [l for l in AAMA_LAYERS if l not in out["layers"]]
        if missing:
            problems.append(f"AAMA layers missing from the LAYER table: {missing}")
        if not inserts:
            problems.append("no INSERT: pieces are not blocks")
        for b in out["blocks"]:
            if b["boundaries"] != 1:
                problems.append(f"block {b['name']}: {b['boundaries']} closed boundaries on layer 1")
            for key in PIECE_TEXT:
                if not any(t.startswith(key) for t in b["texts"]):
                    problems.append(f"block {b['name']}: no `{key}` TEXT on layer 1")
            if b["grain_lines"] > 1:
                problems.append(f"block {b['name']}: {b['grain_lines']} grain LINEs on layer 7")
        if not any(t.dxf.text.startswith("Units:") for t in msp.query("TEXT")):
            problems.append("no `Units:` TEXT in the entities")
    out["problems"] = problems
    if "--resave" in args:
        doc.saveas(args[args.index("--resave") + 1])
    print(json.dumps(out))
    sys.exit(1 if problems or out["audit_errors"] or out["recover_errors"] else 0)


if __name__ == "__main__":
    main()
