#!/usr/bin/env python3
"""How long an edit on the workbench takes to come back flattened, on the graded shoe.

    python3 tools/web/bench-edit.py --flatcut target/release/flatcut [--runs 3]

Starts `flatcut serve` on a copy of patterns/shoe, then per run: draws a style line across the
vamp (`POST /api/lines`, the points taken from the server's own mesh, as the browser test's
clicks are), and times from the line's request to the answer of `POST /api/flatten` (the live view: the base size, which every edit
starts at once) and then `POST /api/flatten?sizes=all` (every size, as the pattern, nest and jobs
need them, and as every edit flattened before); then undoes the line. Prints one line per run
and the medians. A benchmark, not a test: nothing is asserted but the answers' piece counts.
"""

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import tempfile
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def call(base, method, path, body=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(base + path, data=data, method=method,
                                 headers={"content-type": "application/json"})
    with urllib.request.urlopen(req, timeout=600) as r:
        return json.loads(r.read())


def vamp_line(regions):
    """Three mesh vertices across the vamp near x = 210 mm (tests/serve.rs `vamp_line`)."""
    p = regions["parts"][0]["mesh"]["positions"]
    verts = [p[i:i + 3] for i in range(0, len(p), 3)]

    def nearest(t):
        return min(verts, key=lambda v: sum((v[k] - t[k]) ** 2 for k in range(3)))

    return [nearest([210, -60, 0]), nearest([210, 0, 55]), nearest([210, 60, 0])]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--flatcut", default=os.path.join(ROOT, "target/release/flatcut"))
    ap.add_argument("--runs", type=int, default=3)
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="flatcut-bench-edit-")
    for f in ("project.toml", "design.toml"):
        shutil.copy(os.path.join(ROOT, "patterns/shoe", f), work)
    srv = subprocess.Popen([a.flatcut, "serve", os.path.join(work, "project.toml"), "--port", "0"],
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        base = None
        for line in srv.stdout:
            m = re.search(r"workbench: (http://\S+)/", line)
            if m:
                base = m.group(1)
                break
        call(base, "POST", "/api/flatten", {})
        pts = vamp_line(call(base, "GET", "/api/regions"))
        live, graded = [], []
        for run in range(a.runs):
            t0 = time.perf_counter()
            call(base, "POST", "/api/lines", {"part": "upper", "name": f"cut {run}", "points": pts})
            v = call(base, "POST", "/api/flatten", {})
            t1 = time.perf_counter()
            g = call(base, "POST", "/api/flatten?sizes=all", {})
            t2 = time.perf_counter()
            live.append(t1 - t0)
            graded.append(t2 - t1)
            print(f"run {run + 1}: base size {len(v['pieces'])} pieces in {t1 - t0:.3f} s "
                  f"(solve {v['elapsed_s']:.3f} s); every size {len(g['pieces'])} pieces in "
                  f"{t2 - t1:.3f} s (solve {g['elapsed_s']:.3f} s)")
            call(base, "POST", "/api/design/undo")
        print(f"median: base size {statistics.median(live):.3f} s, every size "
              f"{statistics.median(graded):.3f} s ({statistics.median(graded) / statistics.median(live):.1f}×)")
    finally:
        srv.terminate()
        srv.wait(timeout=30)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
