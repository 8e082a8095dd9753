#!/usr/bin/env bash
# Pen-up travel of flatcut's ordering against vpype's linesort on the bench drawing, in one run.
# Usage: tools/gcode/travel_bench.sh [seed]   (needs ../shared beside the repository)
set -euo pipefail
cd "$(dirname "$0")/../.."
seed=${1:-12345}
work=$(mktemp -d)
python3 ../shared/bench/plotter/generate_drawing.py "$work/drawing.svg" "$seed" >/dev/null
VPYPE=${VPYPE:-$work/venv/bin/vpype}
if [ ! -x "$VPYPE" ]; then
  python3 -m venv "$work/venv" && "$work/venv/bin/pip" install --quiet vpype==1.15.0
fi
px_to_mm() { awk -v px="$1" 'BEGIN { printf "%.0f", px * 25.4 / 96 }'; }
stat() { "$VPYPE" read "$work/drawing.svg" "$@" stat 2>/dev/null | awk '/Pen-up length/ { print $NF; exit }'; }
echo "vpype file order:    $(px_to_mm "$(stat)") mm"
echo "vpype linesort:      $(px_to_mm "$(stat linesort)") mm"
echo "vpype linesort 2opt: $(px_to_mm "$(stat linesort --two-opt)") mm"
cargo run --quiet --release -p flatcut-gcode --example travel -- "$work/drawing.svg"
