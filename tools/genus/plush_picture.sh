#!/usr/bin/env bash
# The laid-out pattern of a plush ring (a torus of radii 60 and 20 mm, 1,536 faces) cut by
# `--split auto` within ±10 %, nested with 6 mm seam allowances and the balance notches of its new
# seams, rendered to PNG by headless Chromium: docs/plush-ring-pattern.png.
#
# usage: tools/genus/plush_picture.sh [OUT_PNG]
# needs: python3, chromium; builds the flatcut binary (release) if it is not there.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
png=${1:-$root/docs/plush-ring-pattern.png}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
flatcut=$root/target/release/flatcut
[ -x "$flatcut" ] || (cd "$root" && cargo build --release --bin flatcut)
python3 - "$work/ring.obj" <<'PY'
import math, sys
n, m, r1, r2 = 48, 16, 60.0, 20.0
out = []
for i in range(n):
    for j in range(m):
        u, v = 2 * math.pi * i / n, 2 * math.pi * j / m
        r = r1 + r2 * math.cos(v)
        out.append("v %r %r %r" % (r * math.cos(u), r * math.sin(u), r2 * math.sin(v)))
idx = lambda i, j: (i % n) * m + j % m + 1
for i in range(n):
    for j in range(m):
        out.append("f %d %d %d" % (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)))
        out.append("f %d %d %d" % (idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)))
open(sys.argv[1], "w").write("\n".join(out) + "\n")
PY
"$flatcut" nest "$work/ring.obj" --max-stretch 10 --max-compress 10 --split auto \
  --sheet 500x400 --spacing 4 --seam 6 -o "$work/layout.svg"
printf '<html><body style="margin:0;background:#fff"><img src="layout.svg" style="width:1250px;height:1000px"></body></html>' > "$work/view.html"
chromium --headless --no-sandbox --disable-gpu --window-size=1250,1000 \
  --screenshot="$png" "file://$work/view.html" 2>/dev/null
echo "$png"
