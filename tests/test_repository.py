"""The repository's own shape: no text file that git tracks runs over :data:`MAX_LINES` lines
(docs/design.md, "Layers"; a JSON file keeps its series on few lines: uvms_jax.files.json_text).
A binary file (one with a NUL byte, as git itself tells them) does not count."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAX_LINES = 600
GIT_BINARY_PEEK = 8000  # git calls a file binary when its first 8000 bytes hold a NUL


def tracked_files() -> list[Path]:
    """The files git tracks in this checkout (those present in the working tree)."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    names = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    return [ROOT / n for n in names.decode().split("\0") if n and (ROOT / n).is_file()]


def test_no_tracked_text_file_over_the_line_limit():
    long = []
    for path in tracked_files():
        data = path.read_bytes()
        lines = data.count(b"\n")
        if b"\0" not in data[:GIT_BINARY_PEEK] and lines > MAX_LINES:
            long.append(f"{path.relative_to(ROOT)}: {lines} lines")
    assert not long, f"tracked text files over {MAX_LINES} lines:\n" + "\n".join(long)
