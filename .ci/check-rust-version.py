#!/usr/bin/env python3
"""Fails when the workspace declares a `rust-version` lower than a locked
dependency's.

Reads `cargo metadata --format-version 1 --locked` (every package of
Cargo.lock, all targets and platforms, dev-dependencies included: the
workspace's tests must build with the declared toolchain too) and compares
each workspace member's `rust_version` with the highest `rust_version` among
the other packages. Prints the dependencies that need the most.
Usage: .ci/check-rust-version.py   (from anywhere inside the workspace)
"""
import json
import subprocess
import sys


def version(text):
    return tuple(int(part) for part in text.split("."))


def main():
    out = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--locked"],
        check=True,
        stdout=subprocess.PIPE,
    ).stdout
    meta = json.loads(out)
    members = set(meta["workspace_members"])
    needed = {}
    declared = {}
    for package in meta["packages"]:
        rv = package.get("rust_version")
        if package["id"] in members:
            declared[package["name"]] = rv
        elif rv:
            needed[f'{package["name"]} {package["version"]}'] = version(rv)
    if not needed:
        print("no dependency declares a rust-version")
        return 0
    top = max(needed.values())
    top_text = ".".join(map(str, top))
    by = sorted(name for name, v in needed.items() if v == top)
    failures = []
    for name, rv in sorted(declared.items()):
        if rv is None:
            failures.append(f"{name}: no rust-version (add `rust-version.workspace = true`)")
        elif version(rv) < top:
            failures.append(f"{name}: rust-version {rv} < {top_text}")
    if failures:
        print(f"locked dependencies need Rust {top_text} ({', '.join(by)}):")
        for f in failures:
            print(f"  {f}")
        return 1
    print(f"rust-version ok: dependencies need {top_text} ({', '.join(by)}); "
          f"{len(declared)} workspace members declare at least that")
    return 0


if __name__ == "__main__":
    sys.exit(main())
