"""Cargo.toml's `rust-version` is no older than the newest one any dependency declares.

Reads `cargo metadata` (offline, every feature on, so the Python bindings and the optional
layers count) and compares each package's declared `rust-version` with the crate's own.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def version(text: str) -> tuple[int, ...]:
    parts = [int(p) for p in text.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))


def test_rust_version_covers_every_dependency():
    if shutil.which("cargo") is None:
        pytest.skip("cargo is not installed")
    done = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--offline", "--all-features", "--locked"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    meta = json.loads(done.stdout)
    ours = next(p for p in meta["packages"] if p["name"] == "vsinv" and p["id"] in meta["workspace_members"])
    declared = {
        f"{p['name']} {p['version']}": version(p["rust_version"])
        for p in meta["packages"]
        if p.get("rust_version") and p["id"] not in meta["workspace_members"]
    }
    newest = max(declared.values())
    needing = sorted(name for name, v in declared.items() if v == newest)
    assert version(ours["rust_version"]) >= newest, f"rust-version {ours['rust_version']} < {newest} needed by {needing}"
