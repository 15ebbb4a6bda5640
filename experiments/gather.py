"""Gather a Hydra multirun directory into one CSV and one markdown table.

Every job folder of a sweep (a folder holding ``.hydra/overrides.yaml``) gives one row: the job
number, its overrides (one column per overridden key) and the scalars of its JSON result,
flattened with dotted keys (``solvers.exact.cost``). Lists of scalars are joined with ``;``;
lists of objects (e.g. a GRASP sweep) are left out. A job without its result file is reported
with ``status = missing`` (a crashed job is never silently dropped); a job whose result file or
overrides cannot be read (truncated, garbled) with ``status = broken`` and one line on stderr
naming the file; the other jobs are gathered. Exit status 1 when any job is missing or broken.

Writes ``gathered.csv`` (every column) and ``gathered.md`` into the sweep folder (or ``--out``)
and prints the markdown: the overrides that differ between jobs plus the chosen columns
(``--columns`` patterns, or by default the first 12 columns whose values differ between jobs);
overrides shared by all jobs are listed above the table.

    python experiments/schedule.py --multirun sched/source=synthetic \\
        sched/weights=equal,speed,security,planning_time,only_max_torque \\
        'sched.iterations_sweep=[]' hydra.sweep.dir=multirun/weights
    python experiments/gather.py multirun/weights \\
        --columns 'solvers.*.cost' solvers.exact.path

The result file is ``results.json``, the summary every stage writes (docking, surrogate, plan,
schedule, hardware run, pipeline); folders written before every stage used that name are read
from their older names (``summary.json``, ``report.json``, ``result.json``).
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from uvms_jax.files import write_atomic, write_csv
from uvms_jax.settings import load_yaml

# Every stage's summary, then its older names (docking and plan, surrogate, hardware run).
DEFAULT_FILES = ("results.json", "summary.json", "report.json", "result.json")
FIXED = ("job", "status")
MAX_DEFAULT_COLUMNS = 12  # without --columns, the markdown keeps the first 12 varying columns


def flatten(obj: Any, prefix: str = "") -> dict[str, Any]:
    """Scalars of a JSON object under dotted keys; lists of scalars joined with ``;``."""
    out: dict[str, Any] = {}
    if isinstance(obj, dict):
        for k, v in obj.items():
            out.update(flatten(v, f"{prefix}{k}."))
    elif isinstance(obj, list):
        if all(isinstance(v, (int, float, str, bool)) or v is None for v in obj):
            out[prefix[:-1]] = ";".join(_fmt(v) for v in obj)
    else:
        out[prefix[:-1]] = obj
    return out


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.6g}"
    return "" if v is None else str(v)


def job_dirs(root: Path) -> list[Path]:
    """Job folders under ``root`` (those with ``.hydra/overrides.yaml``), by job number."""
    dirs = [p.parent.parent for p in root.rglob(".hydra/overrides.yaml")]

    def order(p: Path):
        rel = p.relative_to(root).parts
        return tuple((0, int(s), "") if s.isdigit() else (1, 0, s) for s in rel)

    return sorted(dirs, key=order)


def overrides_of(job: Path) -> dict[str, str]:
    """``key=value`` overrides of a job (``hydra.*`` ones left out)."""
    items = load_yaml((job / ".hydra" / "overrides.yaml").read_text()) or []
    out = {}
    for item in items:
        key, _, value = str(item).partition("=")
        key = key.lstrip("+~")
        if not key.startswith("hydra."):
            out[key] = value
    return out


def gather(root: Path, file: str | None = None) -> tuple[list[dict[str, Any]], list[str]]:
    """Rows (one per job) and the override column names."""
    jobs = job_dirs(root)
    if not jobs:
        raise FileNotFoundError(f"{root}: no Hydra job folders (.hydra/overrides.yaml) found")
    if file is None:
        file = next((f for f in DEFAULT_FILES if any((j / f).exists() for j in jobs)), None)
        if file is None:
            raise FileNotFoundError(f"{root}: no job has any of {DEFAULT_FILES}; pass --file")
    rows, override_keys = [], []
    for job in jobs:
        try:
            ov = overrides_of(job)
        except (OSError, UnicodeDecodeError, yaml.YAMLError) as e:
            print(f"gather: {job / '.hydra' / 'overrides.yaml'}: unreadable ({' '.join(str(e).split())}); "
                  "gathered as broken", file=sys.stderr)
            rows.append({"job": str(job.relative_to(root)), "status": "broken"})
            continue
        override_keys += [k for k in ov if k not in override_keys]
        row: dict[str, Any] = {"job": str(job.relative_to(root)), "status": "ok", **ov}
        path = job / file
        if path.exists():
            try:
                result = json.loads(path.read_text())
            except (OSError, UnicodeDecodeError, ValueError) as e:  # a truncated or garbled file
                print(f"gather: {path}: unreadable ({' '.join(str(e).split())}); gathered as broken", file=sys.stderr)
                row["status"] = "broken"
            else:
                row.update({k: v for k, v in flatten(result).items() if k not in row})
        else:
            row["status"] = "missing"
        rows.append(row)
    return rows, override_keys


def select_columns(rows: list[dict[str, Any]], override_keys: list[str], patterns: Sequence[str] | None) -> list[str]:
    """Markdown columns: job, status, overrides, then the pattern matches (in pattern order)
    or, without patterns, every other column whose value differs between jobs."""
    all_cols: list[str] = []
    for r in rows:
        all_cols += [k for k in r if k not in all_cols]
    head = [*FIXED, *override_keys]
    rest = [c for c in all_cols if c not in head]
    if patterns:
        chosen = []
        for pat in patterns:
            chosen += [c for c in rest if fnmatch.fnmatchcase(c, pat) and c not in chosen]
    else:
        chosen = [c for c in rest if len({_fmt(r.get(c)) for r in rows}) > 1][:MAX_DEFAULT_COLUMNS]
    return head + chosen


def to_markdown(rows: list[dict[str, Any]], columns: list[str]) -> str:
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        lines.append("| " + " | ".join(_fmt(r.get(c)).replace("|", "\\|") for c in columns) + " |")
    return "\n".join(lines) + "\n"


def write(rows: list[dict[str, Any]], override_keys: list[str], out: Path,
          patterns: Sequence[str] | None = None) -> tuple[Path, Path]:
    """``gathered.csv`` (all columns) and ``gathered.md`` (selected columns) in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    all_cols = select_columns(rows, override_keys, ["*"])
    csv_path, md_path = out / "gathered.csv", out / "gathered.md"
    write_csv(csv_path, [[_fmt(r.get(c)) for c in all_cols] for r in rows], header=all_cols)
    # Overrides shared by every job go above the table; the table keeps the ones that vary.
    common = [k for k in override_keys if len({str(r.get(k)) for r in rows}) == 1]
    head = f"Common overrides: {', '.join(f'`{k}={rows[0].get(k)}`' for k in common)}\n\n" if common else ""
    columns = [c for c in select_columns(rows, override_keys, patterns) if c not in common]
    write_atomic(md_path, head + to_markdown(rows, columns))
    return csv_path, md_path


class _OneLineErrors(argparse.ArgumentParser):
    """argparse whose usage errors are one line (``gather: error: ...``, exit 2), as the
    experiments' configuration errors; ``--help`` still shows the usage."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (--help: usage)\n")


def main(argv: Sequence[str] | None = None) -> int:
    p = _OneLineErrors(description=__doc__.split("\n\n")[0])
    p.add_argument("sweep_dir", type=Path, help="a multirun folder (hydra.sweep.dir)")
    p.add_argument("--file", help=f"result file in each job folder (default: first of {', '.join(DEFAULT_FILES)})")
    p.add_argument("--columns", nargs="+", metavar="PATTERN",
                   help="markdown columns (fnmatch patterns over the flattened keys); default: the varying ones")
    p.add_argument("--out", type=Path, help="where gathered.csv / gathered.md go (default: the sweep folder)")
    args = p.parse_args(argv)
    try:
        rows, keys = gather(args.sweep_dir, args.file)
    except FileNotFoundError as e:
        print(f"gather: error: {e}", file=sys.stderr)
        return 2
    csv_path, md_path = write(rows, keys, args.out or args.sweep_dir, args.columns)
    print(md_path.read_text(), end="")
    missing = sum(r["status"] == "missing" for r in rows)
    broken = sum(r["status"] == "broken" for r in rows)
    print(f"{len(rows)} jobs ({missing} missing results, {broken} broken) → {csv_path}, {md_path}", file=sys.stderr)
    return 1 if missing or broken else 0


if __name__ == "__main__":
    sys.exit(main())
