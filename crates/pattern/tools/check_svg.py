#!/usr/bin/env python3
"""Third-party check of flatcut pattern SVGs with svgelements (pip install svgelements).

usage: check_svg.py PIECE.svg EXPECTED.json

EXPECTED.json: {"width_mm", "height_mm", "cuts": {"<element id>": {"length_mm", "bbox_mm": [xmin, ymin, xmax, ymax]}}}
with the bbox in SVG coordinates (y down, origin top-left, mm). The document is parsed at
25.4 ppi so one svgelements pixel is one millimetre: the measured cut-line length and bounding
box must equal the piece's within 0.01 mm. Exits non-zero on any mismatch.
"""
import json
import sys

import svgelements

TOL_MM = 0.01


def main() -> int:
    svg_path, expected_path = sys.argv[1], sys.argv[2]
    expected = json.load(open(expected_path))
    doc = svgelements.SVG.parse(svg_path, ppi=25.4)
    failures = []
    if abs(doc.width - expected["width_mm"]) > TOL_MM or abs(doc.height - expected["height_mm"]) > TOL_MM:
        failures.append(f"document size {doc.width} x {doc.height} != {expected['width_mm']} x {expected['height_mm']} mm")
    shapes = {e.id: e for e in doc.elements() if isinstance(e, svgelements.Shape) and e.id}
    for cid, want in expected["cuts"].items():
        if cid not in shapes:
            failures.append(f"{cid}: missing")
            continue
        shape = shapes[cid]
        path = svgelements.Path(shape)
        length = path.length(error=1e-9)
        x0, y0, x1, y1 = path.bbox()
        print(f"{cid}: length {length:.4f} mm (expected {want['length_mm']:.4f}), "
              f"bbox [{x0:.4f}, {y0:.4f}, {x1:.4f}, {y1:.4f}] mm")
        if abs(length - want["length_mm"]) > TOL_MM:
            failures.append(f"{cid}: length {length} != {want['length_mm']}")
        for got, exp in zip((x0, y0, x1, y1), want["bbox_mm"]):
            if abs(got - exp) > TOL_MM:
                failures.append(f"{cid}: bbox {(x0, y0, x1, y1)} != {want['bbox_mm']}")
                break
    for f in failures:
        print("FAIL", f)
    print("OK" if not failures else f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
