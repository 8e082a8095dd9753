#!/usr/bin/env bash
# Builds OptCuts (Li et al. 2018, MIT licence) from a local checkout for the comparison in
# tools/genus/bench.py; nothing of it enters flatcut. Its bundled libigl, Eigen and GLFW are used
# as they are; Intel TBB comes from Debian (its CMake would download a TBB fork).
#
# usage: tools/genus/build_optcuts.sh OPTCUTS_SOURCE_DIR
# needs: apt-get install cmake g++ libtbb-dev libgl1-mesa-dev libx11-dev libxrandr-dev \
#        libxinerama-dev libxcursor-dev libxi-dev libxext-dev libpng-dev
# writes OPTCUTS_SOURCE_DIR/build/OptCuts_bin
set -euo pipefail
src=${1:?usage: build_optcuts.sh OPTCUTS_SOURCE_DIR}
deps="$src/cmake/OptCutsDependencies.cmake"
# Debian's oneTBB instead of the download.
if ! grep -q "find_package(TBB" "$deps"; then
  python3 - "$deps" <<'PY'
import re, sys
p = sys.argv[1]
s = open(p).read()
s = re.sub(r"if\(NOT TARGET TBB::tbb\).*?endif\(\)", "find_package(TBB REQUIRED)", s, flags=re.S)
open(p, "w").write(s)
PY
fi
mkdir -p "$src/build"
cd "$src/build"
nice cmake .. -DCMAKE_BUILD_TYPE=Release > cmake.log 2>&1 || { tail -30 cmake.log; exit 1; }
nice make -j1 OptCuts_bin > make.log 2>&1 || { tail -40 make.log; exit 1; }
ls -l OptCuts_bin
