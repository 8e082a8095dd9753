#!/usr/bin/env python3
"""`flatcut flatten` as a user runs it (read the OBJ, flatten, report, write the OBJ), per mesh
and method: whole-process time and peak memory, Newton steps, and where the time went (the
`--timings` line: read, start map, ordering, assembly, factorisation, solves, line search,
report, write).

usage: python cli_bench.py --flatcut BIN [--methods isometric,lscm] [--repeat N]
                           [--ratio-to isometric] [--out DIR] MESH.obj...

Each run is its own process under /usr/bin/time (wall time and peak RSS of the whole command).
The table gives the median wall time of `--repeat` runs with its CPU time (user + system, less
sensitive to other work on the machine than the wall time) and the stage times of that run,
the largest peak memory, and the machine's one-minute load before and after each mesh (the
machine is shared: compare the ratios of one run, not absolute times). `--ratio-to M` adds each
method's time over method M's on the same mesh in the same run, wall and CPU. Meshes of the shared bench:
`make_meshes.py` (its surfaces at any size through `SURFACES[name](faces)`). A benchmark, never
a test.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

STAGES = ["read", "start", "ordering", "assembly", "factorisation", "solves", "line search",
          "report", "write"]


def timed(cmd):
    """Runs `cmd` under /usr/bin/time; returns (wall s, CPU s, peak MB, exit code, stderr)."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        p = subprocess.run(["/usr/bin/time", "-f", "%e %U %S %M", "-o", tf.name] + cmd,
                           capture_output=True, text=True)
        wall, user, system, kb = open(tf.name).read().split()[-4:]
    return float(wall), float(user) + float(system), int(kb) / 1024.0, p.returncode, p.stderr


def parse(stderr):
    """Newton steps, faces, factorisations, refinement steps (single-precision triangular solves, where
    there were any) and the stage times of flatten's `--timings` output."""
    out = {}
    m = re.search(r"(\d+) faces", stderr)
    if m:
        out["faces"] = int(m.group(1))
    m = re.search(r"(\d+) iterations", stderr)
    if m:
        out["steps"] = int(m.group(1))
    m = re.search(r"factorisation [\d.]+ s \((\d+)\)", stderr)
    if m:
        out["factorisations"] = int(m.group(1))
    m = re.search(r"\((\d+) refinement steps\)", stderr)
    if m:
        out["refinements"] = int(m.group(1))
    for stage in STAGES:
        m = re.search(rf"{stage} ([\d.]+) s", stderr)
        if m:
            out[stage] = float(m.group(1))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--flatcut", required=True, help="the flatcut binary (release build)")
    ap.add_argument("--methods", default="isometric,lscm")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--ratio-to", help="a method whose time the others are divided by")
    ap.add_argument("--out", default=tempfile.mkdtemp(prefix="flatcut-cli-bench-"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    methods = a.methods.split(",")
    print("| mesh | faces | method | s | CPU s | peak MB | steps (factorisations) | "
          + " | ".join(STAGES)
          + (f" | × {a.ratio_to} | × {a.ratio_to} (CPU) |" if a.ratio_to else " |") + " load |")
    print("|---|---|---|---|---|---|---|" + "---|" * len(STAGES) + ("---|---|" if a.ratio_to else "")
          + "---|")
    for mesh in a.meshes:
        stem = os.path.splitext(os.path.basename(mesh))[0]
        times = {}
        cpus = {}
        rows = []
        for method in methods:
            load0 = os.getloadavg()[0]
            runs = []
            for _ in range(a.repeat):
                out = os.path.join(a.out, f"{stem}.{method}.obj")
                wall, cpu, mb, code, err = timed([a.flatcut, "flatten", mesh, "--method", method,
                                             "-o", out, "--timings"])
                if code not in (0, 3):
                    sys.stderr.write(f"{stem} {method}: exit {code}\n{err[-2000:]}\n")
                runs.append((wall, cpu, mb, parse(err)))
            runs.sort(key=lambda r: r[0])
            wall, cpu, _, info = runs[len(runs) // 2]
            peak = max(r[2] for r in runs)
            times[method] = wall
            cpus[method] = cpu
            load = max(load0, os.getloadavg()[0])
            rows.append((method, wall, cpu, peak, info, load))
        for method, wall, cpu, peak, info, load in rows:
            steps = f"{info.get('steps', '–')} ({info.get('factorisations', '–')})"
            stages = " | ".join(f"{info[s]:.2f}" if s in info else "–" for s in STAGES)
            ratio = ""
            if a.ratio_to:
                base, base_cpu = times.get(a.ratio_to), cpus.get(a.ratio_to)
                ratio = f" {wall / base:.2f} | {cpu / base_cpu:.2f} |" if base else " – | – |"
            print(f"| {stem} | {info.get('faces', '–')} | {method} | {wall:.2f} | {cpu:.2f} | {peak:.0f} | "
                  f"{steps} | {stages} |{ratio} {load:.1f} |", flush=True)


if __name__ == "__main__":
    main()
