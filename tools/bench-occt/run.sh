#!/usr/bin/env bash
# Surface evaluation throughput, flatcut vs OpenCASCADE, in one run (issue 2 "Benchmark").
#
# Times point + first partials on the same surfaces and grid as ../shared/bench/occt/eval_occt.cpp
# (bicubic Bézier saddle, 10x10-pole bicubic B-spline) and prints ns/eval and the ratio
# flatcut / OCCT-cached (GeomAdaptor_Surface::D1). Machines are noisy: compare ratios, not times.
#
# Usage: tools/bench-occt/run.sh [N] [REP]     (defaults 1000 5; run from anywhere in the repo)
set -euo pipefail

N="${1:-1000}"
REP="${2:-5}"
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
SRC="$REPO/../shared/bench/occt/eval_occt.cpp"
OUT="${BENCH_OCCT_DIR:-${TMPDIR:-/tmp}/flatcut-bench-occt}"
mkdir -p "$OUT"

if [ ! -f "$SRC" ]; then
  echo "missing $SRC (the OCCT harness lives in ../shared/bench/occt relative to the repo)" >&2
  exit 1
fi

if [ ! -d /usr/include/opencascade ]; then
  echo "== installing OpenCASCADE development packages" >&2
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -qq
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
    libocct-modeling-data-dev libocct-foundation-dev >/dev/null
fi

if [ ! -x "$OUT/eval_occt" ] || [ "$SRC" -nt "$OUT/eval_occt" ]; then
  echo "== building eval_occt" >&2
  g++ -O2 -std=c++17 -I/usr/include/opencascade "$SRC" -o "$OUT/eval_occt" \
    -lTKG3d -lTKG2d -lTKMath -lTKernel
fi

echo "== OpenCASCADE" >&2
"$OUT/eval_occt" "$N" "$REP" | tee "$OUT/occt.txt"
echo "== flatcut" >&2
(cd "$REPO" && cargo bench -q -p flatcut-surface --bench occt_compare -- "$N" "$REP") | tee "$OUT/flatcut.txt"

ns() { # ns/eval of the first line of file $1 matching $2
  grep -F "$2" "$1" | head -n1 | sed -E 's/.* ([0-9.]+) ns\/eval.*/\1/'
}
occt_bez=$(ns "$OUT/occt.txt" "GeomAdaptor_Surface(bezier)::D1")
occt_bsp=$(ns "$OUT/occt.txt" "GeomAdaptor_Surface(bspline)::D1")
geom_bez=$(ns "$OUT/occt.txt" "Geom_BezierSurface::D1")
geom_bsp=$(ns "$OUT/occt.txt" "Geom_BSplineSurface::D1")
fc_bez=$(ns "$OUT/flatcut.txt" "BezierPatch::deriv1")
fc_bsp=$(ns "$OUT/flatcut.txt" "BSplinePatch::deriv1 (10x10 bicubic)")
fc_nurbs=$(ns "$OUT/flatcut.txt" "NURBS")

echo
printf '%-34s %10s %12s %12s %8s\n' "surface (D1, ns/eval)" "flatcut" "OCCT cached" "OCCT Geom_" "ratio"
awk -v a="$fc_bez" -v b="$occt_bez" -v c="$geom_bez" \
  'BEGIN { printf "%-34s %10.1f %12.1f %12.1f %8.2f\n", "bicubic Bezier", a, b, c, a / b }'
awk -v a="$fc_bsp" -v b="$occt_bsp" -v c="$geom_bsp" \
  'BEGIN { printf "%-34s %10.1f %12.1f %12.1f %8.2f\n", "10x10 bicubic B-spline", a, b, c, a / b }'
awk -v a="$fc_nurbs" 'BEGIN { printf "%-34s %10.1f %12s %12s %8s\n", "10x10 bicubic NURBS", a, "-", "-", "-" }'
echo "(ratio = flatcut / OCCT GeomAdaptor_Surface::D1; below 1 means flatcut is faster)"
