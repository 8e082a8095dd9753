#!/usr/bin/env bash
# Rebuilds the workbench's page (crates/server/assets/) from tools/web/src with esbuild.
# The output is deterministic (no timestamps, no source maps, fixed versions from
# package-lock.json), so CI rebuilds it and checks it equals the committed bundle:
#   bash tools/web/build.sh --check
set -euo pipefail
cd "$(dirname "$0")"
out=../../crates/server/assets
check=no
[[ "${1:-}" == "--check" ]] && check=yes
if [[ ! -x node_modules/.bin/esbuild ]]; then
  npm ci --no-audit --no-fund --loglevel=error
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
node_modules/.bin/esbuild src/main.js --bundle --format=esm --target=es2020 --minify \
  --legal-comments=eof --charset=utf8 --log-level=warning --outfile="$tmp/app.js"
cp src/index.html src/app.css "$tmp/"
if [[ $check == yes ]]; then
  for f in index.html app.js app.css; do
    if ! cmp -s "$tmp/$f" "$out/$f"; then
      echo "crates/server/assets/$f differs from what tools/web/build.sh makes of tools/web/src: run tools/web/build.sh and commit" >&2
      exit 1
    fi
  done
  echo "the committed bundle matches its sources"
else
  cp "$tmp/index.html" "$tmp/app.js" "$tmp/app.css" "$out/"
  ls -l "$out"
fi
