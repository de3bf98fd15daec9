#!/usr/bin/env bash
# Live positions (`psdcal serve`), end to end on a simulated recording of
# moving LEDs (simulate-positioning --moving 8):
# - `track --rig --filter cv` on it, its speed against real time (printed);
# - `serve --realtime`: a viewer of /stream gets >= 90 % of the windows with
#   a median lag <= 0.25 s (from the window's last sample, due at
#   start + (t_s + window) on the wall clock, to the event's arrival), the
#   same positions as `track`, and serve exits 0 when the recording ends;
# - the page in headless Chromium (every other host unresolvable), driven
#   by .ci/live-page.py over the DevTools pipe: every sensor named, no console
#   error, no request to another host, and two screenshots 2 s apart differ
#   (and are not blank).
# Usage: .ci/live-test.sh [SCREENSHOT_PREFIX]
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
started=$(date +%s)
command -v chromium >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq chromium >/dev/null; }
work=$(mktemp -d)
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$work"' EXIT
prefix=${1:-$work/live}
cargo build --release --quiet --bin psdcal
psdcal=$(realpath "${CARGO_TARGET_DIR:-target}/release/psdcal")
cd "$work"
"$psdcal" -q simulate-positioning --moving 8 --snr 60 --seed 2 --out sim
args=(--rig sim/rig.json --tones sim/tones.csv --raw sim/raw.tdms --filter cv)
t0=$(date +%s.%N)
"$psdcal" -q track "${args[@]}" > track.csv
t1=$(date +%s.%N)
python3 -c "import sys; d=float(sys.argv[2])-float(sys.argv[1]); print(f'live-test: track --rig --filter cv: 8 s of recording in {d:.2f} s ({8/d:.0f}x real time)')" "$t0" "$t1"

# serve --realtime and one viewer. (Started here, not in a command
# substitution: that would wait for the server's standard output to close.)
serve() { "$psdcal" serve "$@" --realtime --port 0 > /dev/null 2> "$err" & pid=$!; pids+=("$pid"); }
wait_address() { for _ in $(seq 100); do grep -o 'http://[0-9.:]*/' "$err" 2>/dev/null && return; sleep 0.1; done; echo "live-test: FAIL: serve did not listen" >&2; cat "$err" >&2; exit 1; }
err=serve1.err
serve "${args[@]}"
url=$(wait_address)
python3 - "$url" track.csv <<'PY'
import json, statistics, sys, time, urllib.request
url, track = sys.argv[1], sys.argv[2]
rows = [l.rstrip("\n").split(",") for l in open(track)][1:]
events, start = [], None
with urllib.request.urlopen(url + "stream", timeout=60) as r:
    kind = None
    for raw in r:
        line = raw.decode().rstrip("\n")
        if line.startswith("event: "):
            kind = line[7:]
        elif line.startswith("data: "):
            data = json.loads(line[6:])
            if kind == "start":
                start = data
            elif kind == "end":
                break
            else:
                events.append((time.time(), data))
            kind = None
windows = len(rows)
print(f"live-test: {len(events)} events of {windows} rows")
assert len(events) >= 0.9 * windows, "fewer than 90 % of the windows"
lags = [t - (start["unix_s"] + e["t_s"] + start["window_s"]) for t, e in events]
median = statistics.median(lags)
print(f"live-test: lag from a window's last sample to its event: median {median*1000:.0f} ms, "
      f"95th percentile {sorted(lags)[int(0.95*len(lags))]*1000:.0f} ms, max {max(lags)*1000:.0f} ms")
assert median <= 0.25, "median lag above 0.25 s"
by_key = {(round(float(r[0]), 6), r[1]): r for r in rows}
for _, e in events:
    r = by_key[(round(e["t_s"], 6), e["led"])]
    if e["x_world_mm"] is not None:
        assert abs(e["x_world_mm"] - float(r[3])) <= 1e-6 and abs(e["z_world_mm"] - float(r[5])) <= 1e-6, (e, r)
print("live-test: /stream carries the positions of track")
PY
if ! wait "$pid"; then echo "live-test: FAIL: serve did not exit 0" >&2; cat "$err" >&2; exit 1; fi
echo "live-test: serve exited 0 at the end of the recording"

# The page in headless Chromium; every host but 127.0.0.1 unresolvable. A
# longer recording, so that the replay outlasts the page's session (~6 s);
# the server is stopped after it.
"$psdcal" -q simulate-positioning --moving 12 --snr 60 --seed 3 --out sim12
err=serve2.err
serve --rig sim12/rig.json --tones sim12/tones.csv --raw sim12/raw.tdms --filter cv
url=$(wait_address)
python3 "$repo/.ci/live-page.py" "$url" "$prefix" s1 s2 s3 s4
kill "$pid" 2>/dev/null || true
echo "live-test: OK: /stream, track's positions, exit 0, the page renders and moves ($(( $(date +%s) - started )) s)"
