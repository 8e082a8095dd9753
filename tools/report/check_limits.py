#!/usr/bin/env python3
"""Checks a flattened piece against material limits with the shared benchmark's own kernel
(shared/bench/metrics.py `singular_values`), independently of flatcut's report.

usage: check_limits.py FLAT.obj [--max-stretch P] [--max-compress Q]

FLAT.obj is a flattened piece as `flatcut flatten` writes it (`v`, one `vt` per vertex in true mm,
`f a/a b/b c/c`). metrics.py's singular values are taken as they are (true scale: no area
normalisation), so σ1 − 1 is the stretch and 1 − σ2 the compression of each triangle. Prints one
JSON object: the largest stretch and compression in percent, the number of flipped triangles and
whether the limits hold. Exits 0 when they hold, 1 when not, 2 on bad input.
"""
import argparse
import json
import os
import sys

import numpy as np

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "..", "shared", "bench"))
sys.path.insert(0, os.path.dirname(__file__))
from metrics import singular_values  # noqa: E402
from compare_metrics import read_flat_obj  # noqa: E402

# The OBJ stores 6 decimals: a triangle a few mm across moves its stretch by ~1e-6 relative.
ROUNDING = 1e-5


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("obj")
    ap.add_argument("--max-stretch", type=float)
    ap.add_argument("--max-compress", type=float)
    a = ap.parse_args()
    try:
        V, F, UV, FUV = read_flat_obj(a.obj)
    except (OSError, ValueError) as e:
        print(e, file=sys.stderr)
        return 2
    s1, s2, det, _, _ = singular_values(V, F, UV, FUV)
    stretch = float((s1.max() - 1.0) * 100.0)
    compress = float((1.0 - s2.min()) * 100.0)
    flipped = int((det <= 0).sum())
    ok = flipped == 0
    if a.max_stretch is not None:
        ok &= stretch <= a.max_stretch + ROUNDING * 100.0
    if a.max_compress is not None:
        ok &= compress <= a.max_compress + ROUNDING * 100.0
    print(
        json.dumps(
            {
                "stretch_max_pct": stretch,
                "compress_max_pct": compress,
                "flipped": flipped,
                "within_limits": bool(ok),
            }
        )
    )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
