#!/usr/bin/env python3
"""Reads an HP-GL file with ezhpgl (an independent HP-GL interpreter) and prints its pen-down
polylines as JSON: {"completeness": ..., "polylines": [[[x, y], ...], ...]} in millimetres.

Usage: check_ezhpgl.py FILE.plt
"""
import json
import sys

import ezhpgl


def main():
    plot = ezhpgl.readfile(sys.argv[1])
    polylines = []
    for page in plot.pages:
        for op in page.operations:
            g = op.geometry
            if g.kind != "polyline":
                print(json.dumps({"error": f"unexpected geometry {g.kind}"}))
                sys.exit(1)
            polylines.append([[p.x, p.y] for p in g.points])
    print(json.dumps({"ezhpgl": ezhpgl.__version__ if hasattr(ezhpgl, "__version__") else "?",
                      "completeness": str(plot.completeness), "polylines": polylines}))


if __name__ == "__main__":
    main()
