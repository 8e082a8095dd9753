#!/usr/bin/env python3
"""Nesting benchmark: flatcut against sparrow (through its Python wrapper spyrrow) on the ESICUP
strip-packing instances in ../shared/bench/nesting, same machine, same run, alternating runs.

    python tools/nest/bench_vs_sparrow.py --time 60 --seeds 0,1,2 [--instances trousers,shirts]
        [--flatcut target/release/examples/nest_bench] [--out results.jsonl]

Build flatcut's runner first: cargo build --release -p flatcut-nest --example nest_bench.
Both utilizations are measured the same way: total piece area / (H x the strip length the pieces
reach), the length being the largest x of the placed outlines (for sparrow, computed from its
placements; its own figure, which uses its strip width, is reported too).
"""
import argparse, json, math, os, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BENCH = os.path.join(ROOT, "..", "shared", "bench", "nesting")
ALL = ["trousers", "shirts", "swim", "dagli", "mao", "marques", "albano"]


def area(pts):
    return abs(sum(x1 * y2 - x2 * y1 for (x1, y1), (x2, y2) in zip(pts, pts[1:] + pts[:1]))) / 2


def sparrow_run(inst_path, secs, seed, python):
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "sol.json")
        p = subprocess.run([python, os.path.join(BENCH, "run_spyrrow.py"), inst_path, "--time", str(secs),
                            "--seed", str(seed), "--out", out], capture_output=True, text=True, check=True)
        res = json.loads(p.stdout.strip().splitlines()[-1])
        sol = json.load(open(out))
    inst = json.load(open(inst_path))
    shapes = {}
    total = 0.0
    for it in inst["items"]:
        pts = [tuple(q) for q in it["shape"]["data"]]
        if pts[0] == pts[-1]:
            pts = pts[:-1]
        shapes[str(it["id"])] = pts
        total += it["demand"] * area(pts)
    xmax = 0.0
    for pl in sol["placements"]:
        a = math.radians(pl["rotation"])
        c, s = math.cos(a), math.sin(a)
        tx, ty = pl["translation"]
        for (x, y) in shapes[pl["id"]]:
            xmax = max(xmax, c * x - s * y + tx)
    H = float(inst["strip_height"])
    return dict(method="sparrow", length=xmax, utilization=100 * total / (xmax * H),
                own_utilization=100 * res["utilization"], wall_s=res["wall_s"])


def flatcut_run(binary, inst_path, secs, seed):
    p = subprocess.run([binary, inst_path, str(secs), str(seed)], capture_output=True, text=True, check=True)
    r = json.loads(p.stdout.strip().splitlines()[-1])
    return dict(method="flatcut", length=r["length"], utilization=r["utilization"], wall_s=r["time_s"],
                iterations=r["iterations"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--time", type=int, default=60)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--instances", default=",".join(ALL))
    ap.add_argument("--flatcut", default=os.path.join(ROOT, "target", "release", "examples", "nest_bench"))
    ap.add_argument("--python", default=sys.executable, help="a Python with spyrrow installed")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    rows = []
    out = open(a.out, "a") if a.out else None
    for name in a.instances.split(","):
        path = os.path.join(BENCH, "instances", name + ".json")
        for seed in [int(s) for s in a.seeds.split(",")]:
            for method in ("flatcut", "sparrow") if seed % 2 == 0 else ("sparrow", "flatcut"):
                r = flatcut_run(a.flatcut, path, a.time, seed) if method == "flatcut" else \
                    sparrow_run(path, a.time, seed, a.python)
                r.update(instance=name, seed=seed, time_limit_s=a.time)
                rows.append(r)
                print(json.dumps(r), flush=True)
                if out:
                    out.write(json.dumps(r) + "\n")
                    out.flush()
    print()
    print(f"| instance | flatcut mean (seeds) | sparrow mean (seeds) | difference |")
    print("|---|---|---|---|")
    for name in a.instances.split(","):
        f = [r["utilization"] for r in rows if r["instance"] == name and r["method"] == "flatcut"]
        s = [r["utilization"] for r in rows if r["instance"] == name and r["method"] == "sparrow"]
        fm, sm = sum(f) / len(f), sum(s) / len(s)
        print(f"| {name} | {fm:.2f} % ({' / '.join(f'{x:.2f}' for x in f)}) | "
              f"{sm:.2f} % ({' / '.join(f'{x:.2f}' for x in s)}) | {fm - sm:+.2f} |")


if __name__ == "__main__":
    main()
