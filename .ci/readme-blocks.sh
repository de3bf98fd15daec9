#!/usr/bin/env bash
# Runs every ```sh block of README.md, in order, in a fresh copy of the
# repository (the files git tracks, as they are in the work tree: no out/,
# no build), as a newcomer would after installing psdcal. A block preceded
# by the line `<!-- readme-blocks: skip (why) -->` is not run: the test
# command (the run that runs this script), the install (its binary is the
# one CI built) and the main job (.ci/run runs it verbatim; in a copy at
# another path cargo would build the whole workspace again, ~6 minutes).
# The binary on PATH and the cargo target folder are the ones CI built, so
# nothing is compiled again. Usage: .ci/readme-blocks.sh (from anywhere).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
target="$(realpath -m "${CARGO_TARGET_DIR:-$repo/target}")"
test -x "$target/release/psdcal" || (cd "$repo" && cargo build --release --bin psdcal)
copy="$(mktemp -d)"
trap 'rm -rf "$copy"' EXIT
(cd "$repo" && git ls-files -z | xargs -0 cp --parents -t "$copy" 2>/dev/null || true)
test -f "$copy/README.md"
mkdir -p "$copy/.blocks"
python3 - "$copy/README.md" "$copy/.blocks" <<'PY'
import re, sys
text = open(sys.argv[1], encoding="utf-8").read()
n = 0
for m in re.finditer(r"(?:^(<!-- readme-blocks: skip[^\n]*-->)\n)?^```sh\n(.*?)^```", text, re.M | re.S):
    n += 1
    skip, body = m.group(1), m.group(2)
    name = f"{sys.argv[2]}/{n:02d}{'-skip' if skip else ''}.sh"
    open(name, "w", encoding="utf-8").write(body)
print(f"{n} shell blocks in README.md")
PY
export PATH="$target/release:$PATH" CARGO_TARGET_DIR="$target"
cd "$copy"
sleep 1
touch .blocks/start
for block in .blocks/*.sh; do
    if [[ "$block" == *-skip.sh ]]; then
        echo "-- skipped (marked): $(head -c 60 "$block" | head -n 1)"
        continue
    fi
    echo "-- running $block:"
    sed 's/^/   $ /' "$block"
    bash -euo pipefail "$block" >"$block.log" 2>&1 || {
        cat "$block.log"
        echo "README block $block failed" >&2
        exit 1
    }
done
# Every result is under out/: nothing else appeared or changed in the copy.
extra="$(find . -path ./out -prune -o -path ./.blocks -prune -o -mindepth 1 -newer .blocks/start ! -type d -print | head -5)"
if [ -n "$extra" ]; then
    echo "README blocks wrote outside out/: $extra" >&2
    exit 1
fi
echo "README blocks: every block ran in a fresh copy, results under out/ only"
