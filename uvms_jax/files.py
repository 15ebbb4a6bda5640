"""Result files that are never half-written, and run folders that say when a run did not end.

* :func:`write_atomic` / :func:`atomic_path` / :func:`write_csv`: a file is written to a temporary file in its own
  folder, flushed to disk, then renamed over the target (``os.replace``, atomic on POSIX and
  Windows): a reader sees the old file or the new one, never a part; a run killed while writing
  leaves at most a ``.*.tmp`` file beside it, never a truncated result.
* :func:`json_text` / :func:`write_json`: the one layout of every JSON result file (benchmark
  records, run results, plans): indented, but with lists of numbers and small records kept on
  one line, so a file of long series stays short and diffs line by line.
* :data:`RUNNING`: the marker a run folder carries while a run writes into it
  (:func:`mark_running`, :func:`clear_running`). A folder that still has it after its process
  is gone holds a run that was killed (SIGKILL, power loss): its results, if any, are partial.
* :func:`used_run_folder`: why a folder must not take a new run (it holds an earlier run's
  results or a marker), in one line naming the marker's run and when it started; every runner
  (``uvms-hw run``, the pipeline) refuses such a folder unless told to overwrite it
  (:func:`refuse_used_folder`).
* :func:`sigterm_as_interrupt`: SIGTERM, which batch schedulers send before they kill a job,
  stops a run the way Ctrl-C (SIGINT) does: partial results marked ``interrupted``, exit
  :data:`EXIT_TERMINATED`.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import signal
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["EXIT_INTERRUPTED", "EXIT_TERMINATED", "RUNNING", "UsedFolderError", "atomic_path", "clear_running",
           "json_text", "mark_running", "marker_summary", "refuse_used_folder", "sigterm_as_interrupt", "used_run_folder",
           "write_atomic", "write_csv", "write_json"]

RUNNING = "RUNNING"  # the marker file's name in a run folder
# Exit statuses of a run stopped by a signal: 128 + the signal's number, as shells report them.
EXIT_INTERRUPTED = 128 + signal.SIGINT  # 130: Ctrl-C
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143: a batch scheduler's (or `kill`'s) SIGTERM
# json_text's layout: a list or object whose one-line form, with its indentation and key, takes at
# most SHORT_LINE characters stays on one line; a list of one-line items (numbers, records) takes
# lines of at most LONG_LINE characters (a record longer than that has a line of its own).
SHORT_LINE = 100
LONG_LINE = 1000


class UsedFolderError(FileExistsError):
    """A run folder that holds an earlier run (:func:`used_run_folder`'s one line)."""


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


def json_text(obj: Any, *, indent: int = 1, default: Callable[[Any], Any] | None = None,
              ensure_ascii: bool = True) -> str:
    """``obj`` as JSON text (no final newline), as ``json.dumps(obj, indent=indent, ...)`` would
    write it but for what stays on one line: a record (an object of scalars), a list or object
    whose one-line form fits :data:`SHORT_LINE`, and a list of one-line items (numbers, strings,
    records) that fits :data:`LONG_LINE`; a longer such list fills lines of up to
    :data:`LONG_LINE` characters. A list of lists (a matrix, a path of waypoints) keeps a row a
    line. ``json.loads`` of the text gives what ``json.dumps`` of ``obj`` would."""
    def one_line(o: Any) -> str:
        return json.dumps(o, default=default, ensure_ascii=ensure_ascii)

    def scalar(o: Any) -> bool:
        return not isinstance(o, (dict, list, tuple))

    def block(opening: str, lines: list[str], closing: str, depth: int) -> str:
        inner = " " * (indent * (depth + 1))
        return opening + "\n" + ",\n".join(inner + line for line in lines) + "\n" + " " * (indent * depth) + closing

    def render(o: Any, depth: int, lead: int) -> tuple[str, bool]:
        """(text, whether it is one line) of ``o`` at ``depth``, after ``lead`` characters of key."""
        text = one_line(o)
        if scalar(o) or not o or (isinstance(o, dict) and all(map(scalar, o.values()))) \
                or len(text) <= SHORT_LINE - indent * depth - lead:
            return text, True
        if isinstance(o, dict):
            keys = [one_line({k: None})[1:-len(": null}")] + ": " for k in o]  # JSON's own text of each key
            return block("{", [k + render(v, depth + 1, len(k))[0] for k, v in zip(keys, o.values())], "}", depth), False
        items = [render(x, depth + 1, 0) for x in o]
        rows = [t for t, _ in items]
        if not all(flat for _, flat in items) or any(isinstance(x, (list, tuple)) for x in o):
            return block("[", rows, "]", depth), False
        if len(text) <= LONG_LINE - indent * depth - lead:
            return text, True
        return block("[", _fill(rows, LONG_LINE - indent * (depth + 1)), "]", depth), False

    return render(obj, 0, 0)[0]


def _fill(items: list[str], width: int) -> list[str]:
    """``items`` joined by ``", "`` into lines of at most ``width`` characters (an item longer
    than that on a line of its own)."""
    lines = [items[0]]
    for item in items[1:]:
        if len(lines[-1]) + 2 + len(item) > width:
            lines.append(item)
        else:
            lines[-1] += ", " + item
    return lines


def write_json(path: Path | str, obj: Any, **layout) -> Path:
    """Write ``obj`` to ``path`` atomically (:func:`write_atomic`) as :func:`json_text` (with its
    keyword arguments ``layout``) and a final newline."""
    return write_atomic(path, json_text(obj, **layout) + "\n")


def write_csv(path: Path | str, rows: Iterable[Sequence] | Sequence[Mapping], header: Sequence[str] | None = None) -> Path:
    """Write a CSV table to ``path`` atomically (:func:`atomic_path`): ``header`` then ``rows``
    (sequences), or, without ``header``, ``rows`` as mappings under the first one's keys.

    Raises:
      ValueError: no header and no rows (the columns are unknown).
    """
    path = Path(path)
    if header is None:
        rows = list(rows)
        if not rows:
            raise ValueError(f"{path.name}: no header and no rows; the columns are unknown")
        header = list(rows[0])
        rows = [[row[k] for k in header] for row in rows]
    with atomic_path(path) as tmp, tmp.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows(rows)
    return path


def mark_running(folder: Path | str, **info) -> Path:
    """Put the :data:`RUNNING` marker into ``folder`` (created): JSON with the process id, the
    start time and the command line, plus ``info``. Returns the marker's path."""
    folder = Path(folder)
    body = {"pid": os.getpid(), "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "argv": sys.argv, **info}
    return write_json(folder / RUNNING, body, default=str)


def clear_running(folder: Path | str) -> None:
    """Remove ``folder``'s :data:`RUNNING` marker (no error if it has none)."""
    (Path(folder) / RUNNING).unlink(missing_ok=True)


def marker_summary(folder: Path | str) -> str:
    """The :data:`RUNNING` marker of ``folder`` in words: the process that wrote it, when it
    started, its command line and, for a run that stopped, its status and stage (one line)."""
    try:
        body = json.loads((Path(folder) / RUNNING).read_text())
        if not isinstance(body, dict):
            raise ValueError("not a JSON object")
    except (OSError, UnicodeDecodeError, ValueError) as e:
        return f"an unreadable marker ({type(e).__name__})"
    argv = body.get("argv")
    command = " ".join(map(str, argv)) if isinstance(argv, list) else "?"
    status = f", {body['status']} in stage {body.get('stage')}" if body.get("status") else ", no status (killed?)"
    return f"the run of pid {body.get('pid', '?')} started {body.get('started', '?')} (`{command}`){status}"


def used_run_folder(folder: Path | str, names: Sequence[str], retry: str) -> str | None:
    """Why ``folder`` must not take a new run, or None when it may: it holds any of ``names``
    (an earlier run's results, or its :data:`RUNNING` marker, whose run is named by
    :func:`marker_summary`). ``retry`` says what to do instead, e.g. ``"choose another --out
    or pass --overwrite"``. One line."""
    found = [name for name in names if (Path(folder) / name).exists()]
    if not found:
        return None
    marker = f"; the marker is {marker_summary(folder)}" if RUNNING in found else ""
    return f"{folder} already holds a run ({', '.join(found)}{marker}): {retry}"


def refuse_used_folder(folder: Path | str, names: Sequence[str], retry: str) -> None:
    """Raise :class:`UsedFolderError` with :func:`used_run_folder`'s line if ``folder`` holds any
    of ``names``."""
    refusal = used_run_folder(folder, names, retry)
    if refusal is not None:
        raise UsedFolderError(refusal)


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[Callable[[], bool]]:
    """Within the block, SIGTERM raises ``KeyboardInterrupt`` as SIGINT does, so a run stops the
    way Ctrl-C stops it (the arm told to hold, partial results written and marked
    ``interrupted``). Yields a function telling whether SIGTERM arrived: the caller then exits
    with :data:`EXIT_TERMINATED` instead of :data:`EXIT_INTERRUPTED`. Outside the main thread
    (where no handler can be set) SIGTERM keeps its default."""
    received: list[int] = []

    def handler(signum, frame):
        received.append(signum)
        raise KeyboardInterrupt("SIGTERM")

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread
        yield lambda: False
        return
    try:
        yield lambda: bool(received)
    finally:
        signal.signal(signal.SIGTERM, previous)
