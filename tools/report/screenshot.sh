#!/usr/bin/env bash
# Renders a self-contained `flatcut report --html` page in headless Chromium and fails when the
# screenshot is missing or nearly blank, so a report that renders to an empty page (an SVG with a
# broken viewBox, a page that never finished loading) is caught before a person opens it.
#
# usage: tools/report/screenshot.sh REPORT.html OUT.png
# env:   CHROMIUM (default: /usr/bin/chromium), WINDOW (default: 1400,2000),
#        MIN_INK (minimum fraction of non-white pixels, default 0.02)
set -euo pipefail

if [[ $# -ne 2 ]]; then
    echo "usage: $0 REPORT.html OUT.png" >&2
    exit 2
fi
html=$1
out=$2
chromium=${CHROMIUM:-/usr/bin/chromium}
window=${WINDOW:-1400,2000}
min_ink=${MIN_INK:-0.02}

if [[ ! -f $html ]]; then
    echo "$html: no such file" >&2
    exit 2
fi
if [[ ! -x $chromium ]]; then
    echo "$chromium not found: install it with 'apt-get update && apt-get install -y chromium'" >&2
    exit 2
fi
if ! python3 -c 'import PIL' 2>/dev/null; then
    echo "Pillow missing: pip install -r tools/requirements.txt" >&2
    exit 2
fi

url="file://$(realpath "$html")"
out_abs="$(realpath -m "$out")"
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
rm -f "$out_abs"

# A fresh profile and no background traffic: the page is self-contained and must render offline.
timeout 120 "$chromium" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --hide-scrollbars --user-data-dir="$profile" --window-size="$window" \
    --screenshot="$out_abs" "$url" >"$profile/chromium.log" 2>&1 || {
    echo "chromium failed on $html:" >&2
    tail -n 20 "$profile/chromium.log" >&2
    exit 1
}

python3 - "$out_abs" "$min_ink" <<'PY'
import sys
from PIL import Image

path, min_ink = sys.argv[1], float(sys.argv[2])
try:
    img = Image.open(path).convert("RGB")
except (OSError, ValueError) as e:
    sys.exit(f"{path}: no readable PNG ({e})")
w, h = img.size
# A pixel carries ink when any channel is clearly below white (anti-aliasing halos excluded).
INK_LEVEL = 240
pixels = getattr(img, "get_flattened_data", img.getdata)()  # getdata is deprecated in Pillow 13
ink = sum(1 for px in pixels if min(px) < INK_LEVEL)
frac = ink / float(w * h)
print(f"{path}: {w}x{h} px, {ink} non-white pixels ({frac:.2%})")
if frac < min_ink:
    sys.exit(f"{path}: nearly blank ({frac:.2%} < {min_ink:.2%} non-white)")
PY
