#!/usr/bin/env bash
# Runs the README's main command (the bundled shoe project, streamed to the embedded simulator)
# exactly as a new user would, then checks that every promised output exists.
set -euo pipefail
cd "$(dirname "$0")/../.."
cmd=$(grep -E '^cargo run .* run patterns/' README.md | head -n 1)
[ -n "$cmd" ] || { echo "README.md has no 'cargo run … run patterns/…' command" >&2; exit 1; }
echo "+ $cmd --quiet"
out=$(mktemp -d)
eval "$cmd --quiet -o $out"
for f in report.json report.html heatmap.svg heatmap.png pattern.svg pattern.dxf layout-1.svg job-1.gcode sim-1.svg summary.json; do
  [ -s "$out/$f" ] || { echo "missing output: $f" >&2; exit 1; }
done
echo "main command: all outputs written to $out"
