"""Result files that are never half-written, and run folders that say when a run did not end.

* :func:`write_atomic` / :func:`atomic_path`: a file is written to a temporary file in its own
  folder, flushed to disk, then renamed over the target (``os.replace``, atomic on POSIX and
  Windows): a reader sees the old file or the new one, never a part; a run killed while writing
  leaves at most a ``.*.tmp`` file beside it, never a truncated result.
* :data:`RUNNING`: the marker a run folder carries while a run writes into it
  (:func:`mark_running`, :func:`clear_running`). A folder that still has it after its process
  is gone holds a run that was killed (SIGKILL, power loss): its results, if any, are partial.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

__all__ = ["RUNNING", "atomic_path", "clear_running", "mark_running", "write_atomic"]

RUNNING = "RUNNING"  # the marker file's name in a run folder


@contextlib.contextmanager
def atomic_path(path: Path | str) -> Iterator[Path]:
    """A temporary path in ``path``'s folder to write to; renamed over ``path`` when the block
    ends without an exception, removed when it raises (``path`` is then left as it was).

    The folder is created. Use for writers that want a file name (CSV writers, ``savefig``)::

        with atomic_path(out / "run.png") as tmp:
            fig.savefig(tmp, format="png")
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        with open(tmp, "rb+") as f:  # the bytes reach the disk before the name does
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)  # mkstemp makes it 0600; results are ordinary files
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_atomic(path: Path | str, data: str | bytes) -> Path:
    """Write ``data`` (text as UTF-8, or bytes) to ``path`` atomically (:func:`atomic_path`)."""
    path = Path(path)
    with atomic_path(path) as tmp:
        if isinstance(data, str):
            tmp.write_text(data, encoding="utf-8")
        else:
            tmp.write_bytes(data)
    return path


def mark_running(folder: Path | str, **info) -> Path:
    """Put the :data:`RUNNING` marker into ``folder`` (created): JSON with the process id, the
    start time and the command line, plus ``info``. Returns the marker's path."""
    folder = Path(folder)
    body = {"pid": os.getpid(), "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "argv": sys.argv, **info}
    return write_atomic(folder / RUNNING, json.dumps(body, indent=1, default=str) + "\n")


def clear_running(folder: Path | str) -> None:
    """Remove ``folder``'s :data:`RUNNING` marker (no error if it has none)."""
    (Path(folder) / RUNNING).unlink(missing_ok=True)
