#!/usr/bin/env bash
# Browser test of `psdcal report`, `psdcal evaluate --report`,
# `psdcal study --report` (a small study: Table 1 and Figure 9, 3 trials) and
# `psdcal psd-map --report` (a 0.25 mm simulated scan, under a second): each page
# renders in headless Chromium at 1200 px and at 390 px (a phone) without
# console errors, and its screenshots are not blank.
#
# Installs Debian's `chromium` when it is missing (CI runs as root).
# Usage: .ci/browser-test.sh [SCREENSHOT_PREFIX]   (default: a temporary folder;
#        writes PREFIX-report-1200.png, PREFIX-report-390.png, PREFIX-evaluation-….png,
#        PREFIX-study-….png, PREFIX-psd_map-….png)
set -euo pipefail
cd "$(dirname "$0")/.."
started=$(date +%s)

if ! command -v chromium >/dev/null 2>&1; then
    echo "browser-test: installing chromium"
    apt-get update -qq && apt-get install -y -qq chromium >/dev/null
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=${1:-$work/shot}

cargo build --release --quiet --bin psdcal
psdcal=${CARGO_TARGET_DIR:-target}/release/psdcal
"$psdcal" -q simulate --lens 2 --snr 40 --out "$work/sim"
"$psdcal" -q calibrate -t "$work/sim/template.csv" -o "$work/sim/observations.csv" \
    --out "$work/sim/calibration.json"
"$psdcal" -q report -c "$work/sim/calibration.json" -t "$work/sim/template.csv" \
    -o "$work/sim/observations.csv" --out "$work/report"

"$psdcal" -q simulate-positioning --lens 2 --snr 40 --emitters 60 --out "$work/room"
"$psdcal" -q locate --rig "$work/room/rig.json" --points "$work/room/rig_points.csv" \
    --point-sigma 0.0007 --out "$work/room/estimates.csv"
"$psdcal" -q evaluate --truth "$work/room/truth.csv" --estimates "$work/room/estimates.csv" \
    --rig "$work/room/rig.json" --report "$work/evaluation"
"$psdcal" -q simulate-scan --step 0.25 --stage-sigma 0.3 --snr 50 --out "$work/scan.csv"
"$psdcal" -q psd-map --scan "$work/scan.csv" --out "$work/psd_map.json" --report "$work/psd-map-page"
# The cheapest study with every part of the page (tables, the bias, the
# paper's numbers, Figure 9's heat maps, histograms): a few seconds.
"$psdcal" -q study table1 fig9 --trials 3 --out "$work/study" --report "$work/study-page"

# check_page NAME PAGE WIDTH: render PAGE at WIDTH px; fail on a script,
# console errors, or a (nearly) blank screenshot.
check_page() {
    local name=$1 page=$2 width=$3
    local shot="$prefix-$name-$width.png"
    if grep -qi '<script' "$page"; then
        echo "browser-test: FAIL: $name holds a <script> element" >&2
        exit 1
    fi
    # Headless Chromium, nothing on the network: console messages are logged
    # on standard error as CONSOLE(...) lines.
    timeout 120 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
        --disable-background-networking --disable-component-update --disable-sync \
        --user-data-dir="$work/profile" --enable-logging=stderr --v=0 \
        --hide-scrollbars --window-size="$width,1400" \
        --screenshot="$shot" "file://$page" >"$work/chromium.out" 2>"$work/chromium.err" || {
        echo "browser-test: FAIL: chromium exited with an error on $name at $width px:" >&2
        tail -20 "$work/chromium.err" >&2
        exit 1
    }
    if grep -E 'CONSOLE|Refused to|Uncaught' "$work/chromium.err" >&2; then
        echo "browser-test: FAIL: $name logged console errors at $width px (above)" >&2
        exit 1
    fi
    if [ ! -s "$shot" ]; then
        echo "browser-test: FAIL: no screenshot of $name at $width px" >&2
        tail -20 "$work/chromium.err" >&2
        exit 1
    fi
    not_blank "$shot"
    echo "browser-test: $name renders at $width px"
}

not_blank() {
# Not blank: decode the PNG (standard library only) and count the colours.
python3 - "$1" <<'PY'
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
pos, idat, width, height, ctype, depth = 8, b"", 0, 0, 0, 0
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + n]
    if kind == b"IHDR":
        width, height, depth, ctype = struct.unpack(">IIBB", body[:10])
    elif kind == b"IDAT":
        idat += body
    pos += 12 + n
raw = zlib.decompress(idat)
bpp = {2: 3, 6: 4, 0: 1, 4: 2}[ctype] * depth // 8
stride = width * bpp
colours, prev, k = set(), bytearray(stride), 0
for _ in range(height):
    f, line = raw[k], bytearray(raw[k + 1:k + 1 + stride])
    k += 1 + stride
    for i in range(stride):
        a = line[i - bpp] if i >= bpp else 0
        b, c = prev[i], (prev[i - bpp] if i >= bpp else 0)
        if f == 1: line[i] = (line[i] + a) & 255
        elif f == 2: line[i] = (line[i] + b) & 255
        elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    for i in range(0, stride, bpp * 7):
        colours.add(bytes(line[i:i + bpp]))
    prev = line
print(f"browser-test: screenshot {width}x{height}, {len(colours)} distinct sampled colours")
if len(colours) < 50:
    sys.exit("browser-test: FAIL: the screenshot is (nearly) blank")
PY
}

for width in 1200 390; do
    check_page report "$work/report/report.html" "$width"
    check_page evaluation "$work/evaluation/evaluation.html" "$width"
    check_page study "$work/study-page/study.html" "$width"
    check_page psd_map "$work/psd-map-page/psd_map.html" "$width"
done
echo "browser-test: OK: report.html, evaluation.html, study.html and psd_map.html render without console errors at 1200 and 390 px ($(( $(date +%s) - started )) s)"
