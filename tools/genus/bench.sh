#!/usr/bin/env bash
# Closed surfaces of several genera through `flatcut flatten --split auto` against OptCuts, in one
# run, both scored by the bench's metrics.py (tools/flatten/darts_bench.py does the measuring).
#
# usage: tools/genus/bench.sh OUT_DIR [STRETCH COMPRESS [OPTCUTS_SOURCE_DIR]]
# env: BENCH (the shared bench with metrics.py; ../shared/bench), SPLIT_TIME (flatcut's --split-time, s; 240), TIMEOUT (per mesh and tool, s; 900), MESHES
# (names, space-separated; the nine below)
# needs: python3 with numpy; for the meshes Debian's libcgal-demo (downloaded here with
# apt-get download); for OptCuts its source (tools/genus/build_optcuts.sh builds it).
set -euo pipefail
out=${1:?usage: bench.sh OUT_DIR [STRETCH COMPRESS [OPTCUTS_SOURCE_DIR]]}
stretch=${2:-5}
compress=${3:-5}
optcuts=${4:-}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
mkdir -p "$out/cgal" "$out/meshes"
if [ ! -d "$out/cgal/data/meshes" ]; then
  (cd "$out/cgal" && apt-get download libcgal-demo && dpkg-deb -x libcgal-demo_*.deb x \
    && tar xzf x/usr/share/doc/libcgal-dev/data.tar.gz)
fi
python3 "$here/make_meshes.py" "$out/cgal/data/meshes" "$out/meshes"
(cd "$root" && cargo build --release --bin flatcut)
extra=()
if [ -n "$optcuts" ]; then
  [ -x "$optcuts/build/OptCuts_bin" ] || "$here/build_optcuts.sh" "$optcuts"
  extra=(--optcuts "$optcuts/build/OptCuts_bin")
fi
meshes=()
for m in ${MESHES:-sphere torus eight knot1 elephant boot12 bull bear bunny00}; do meshes+=("$out/meshes/$m.obj"); done
python3 "$root/tools/flatten/darts_bench.py" --bench "${BENCH:-$root/../shared/bench}" \
  --flatcut "$root/target/release/flatcut" --flatcut-args "--max-pieces 64 --split-time ${SPLIT_TIME:-240}" \
  --stretch "$stretch" --compress "$compress" --timeout "${TIMEOUT:-900}" --out "$out/runs" "${extra[@]}" "${meshes[@]}"
