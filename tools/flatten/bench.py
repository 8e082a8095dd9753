#!/usr/bin/env python3
"""flatcut's flattening against libigl's SLIM in one run: per mesh, Newton steps, solve seconds,
peak memory and δ2 (symmetric Dirichlet, scored by the bench's metrics.py for both).

usage: python bench.py --bench ../shared/bench [--flatcut LABEL=BIN]... [--threads N]
                       [--method isometric] [--no-slim] [--out DIR] MESH.obj...

BIN is the `flatten_bench` example of crates/flatten
(`cargo build --release -p flatcut-flatten --example flatten_bench` → target/release/examples/flatten_bench);
several `--flatcut` give several columns (e.g. two builds, or the same build with different
thread counts via `--threads`). Each solve runs in its own process under /usr/bin/time, so the
peak memory (max RSS) is that solve's. Prints a Markdown table; ratios are against SLIM's time
on the same mesh in the same run.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np


def timed(cmd, env=None):
    """Runs `cmd` under /usr/bin/time; returns (stdout, max RSS in MB)."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        p = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", tf.name] + cmd,
                           capture_output=True, text=True, env=env)
        try:
            rss = int(open(tf.name).read().strip().splitlines()[-1]) / 1024.0
        except (ValueError, IndexError):
            rss = float("nan")
    if p.returncode != 0:
        sys.stderr.write(p.stderr[-2000:])
    return p.stdout, rss


def last_json(text):
    for line in reversed(text.strip().splitlines()):
        if line.startswith("{"):
            return json.loads(line)
    return {}


def score(bench, path):
    """The bench's metrics of an OBJ with `v`, `vt` and `f a/a b/b c/c` (flatcut's output)."""
    sys.path.insert(0, bench)
    from metrics import distortion_metrics  # noqa: E402

    V, UV, F, FT = [], [], [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                V.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("vt "):
                UV.append([float(x) for x in line.split()[1:3]])
            elif line.startswith("f "):
                c = [tok.split("/") for tok in line.split()[1:4]]
                F.append([int(a[0]) - 1 for a in c])
                FT.append([int(a[1]) - 1 if len(a) > 1 and a[1] else int(a[0]) - 1 for a in c])
    m = distortion_metrics(np.array(V), np.array(F), np.array(UV), np.array(FT), check_overlap=False)
    return m


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--bench", required=True, help="the shared bench directory (metrics.py, flatten_anchor.py)")
    ap.add_argument("--flatcut", action="append", default=[], help="LABEL=BIN of the bench example")
    ap.add_argument("--threads", type=int)
    ap.add_argument("--method", default="isometric")
    ap.add_argument("--no-slim", action="store_true")
    ap.add_argument("--slim-iters", type=int, default=0)
    ap.add_argument("--out", default=tempfile.mkdtemp(prefix="flatcut-bench-"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    tools = [f.split("=", 1) for f in a.flatcut]
    print("| mesh | faces | solver | Newton steps | s | peak MB | δ2 mean | δ2 max | flips | time / SLIM's |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for mesh in a.meshes:
        stem = os.path.splitext(os.path.basename(mesh))[0]
        rows = []
        slim_s = None
        if not a.no_slim:
            out = os.path.join(a.out, f"{stem}.slim.obj")
            cmd = [sys.executable, os.path.join(a.bench, "flatten_anchor.py"), mesh, "igl_slim_symd",
                   "--out", out, "--no-overlap-check"]
            if a.slim_iters:
                cmd += ["--iters", str(a.slim_iters)]
            text, rss = timed(cmd)
            r = last_json(text)
            slim_s = r.get("seconds")
            rows.append(("libigl SLIM", r.get("n_faces"), r.get("iterations"), slim_s, rss,
                         r.get("symd_mean"), r.get("symd_max"), r.get("n_flipped")))
        for label, binary in tools:
            out_dir = os.path.join(a.out, label)
            os.makedirs(out_dir, exist_ok=True)
            cmd = [binary, "--method", a.method, "--out", out_dir, mesh]
            if a.threads:
                cmd[1:1] = ["--threads", str(a.threads)]
            text, rss = timed(cmd)
            r = last_json(text)
            uv = os.path.join(out_dir, f"{stem}.{a.method}.flatcut.obj")
            m = score(a.bench, uv) if os.path.exists(uv) and "error" not in r else {}
            rows.append((f"flatcut {label}", r.get("faces"), r.get("iterations"), r.get("seconds"), rss,
                         m.get("symd_mean"), m.get("symd_max"), m.get("n_flipped")))
        for name, faces, steps, s, rss, d2, d2max, flips in rows:
            ratio = f"{s / slim_s:.3f}" if s is not None and slim_s else "–"
            fmt = lambda v, f: (f % v) if isinstance(v, (int, float)) else "–"  # noqa: E731
            print(f"| {stem} | {faces} | {name} | {steps} | {fmt(s, '%.3f')} | {fmt(rss, '%.0f')} | "
                  f"{fmt(d2, '%.6f')} | {fmt(d2max, '%.3f')} | {flips} | {ratio} |", flush=True)


if __name__ == "__main__":
    main()
