"""What each stage contributes to ``summary.md`` and ``results.json``, and the writer of both."""

from __future__ import annotations

import dataclasses
import math
import os
import platform
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import jax

from uvms_jax.files import write_atomic
from uvms_jax.text import md_table

__all__ = ["StageReport", "write_summary"]


@dataclasses.dataclass
class StageReport:
    """A stage's part of the summary.

    Attributes:
      name: stage name, also its folder in the run directory.
      title: section heading of ``summary.md``.
      tables: markdown tables.
      results: key figures (JSON-serialisable) for ``results.json`` and sweeps.
      notes: markdown paragraphs after the tables.
      seconds: wall time of the stage [s] (JAX compilation included).
      cpu_seconds: process CPU time over all threads [s]: a load-independent size of the work.
    """

    name: str
    title: str
    tables: list[str] = dataclasses.field(default_factory=list)
    results: dict[str, Any] = dataclasses.field(default_factory=dict)
    notes: list[str] = dataclasses.field(default_factory=list)
    seconds: float = math.nan
    cpu_seconds: float = math.nan


def write_summary(out: Path, reports: Sequence[StageReport], total_s: float, config_yaml: str, chain: str = "") -> Path:
    """``out/summary.md``: the chain at a glance, stage times, every stage's tables and notes,
    links to its PNGs, the config."""
    dev = jax.devices()[0]
    lines = ["# uvms_jax pipeline run", "",
             f"{time.strftime('%Y-%m-%d %H:%M:%S')} · {platform.machine()}, {os.cpu_count()} CPUs, "
             f"device {dev.platform} ({dev.device_kind}) · Python {platform.python_version()}, jax {jax.__version__} · "
             f"load average {', '.join(f'{v:.1f}' for v in os.getloadavg())} · total wall time **{total_s:.1f} s**", ""]
    if chain:
        lines += ["## The intervention at a glance", "", chain, ""]
    lines += ["## Stage times", "",
             md_table(["stage", "folder", "wall [s]", "CPU [s]"],
                      [[r.title.split(" (")[0], f"[{r.name}/]({r.name}/)", r.seconds, r.cpu_seconds] for r in reports]
                      + [["total", "", total_s, sum(r.cpu_seconds for r in reports)]]), "",
             "Wall times include JAX/XLA compilation. CPU = process CPU time over all threads; on a busy "
             "machine wall time exceeds it by the share other jobs take.", ""]
    for r in reports:
        lines += [f"## {r.title}", ""]
        for t in r.tables:
            lines += [t, ""]
        for n in r.notes:
            lines += [n, ""]
        pngs = sorted((out / r.name).rglob("*.png"))
        if pngs:
            lines += ["Figures: " + " · ".join(f"[{p.relative_to(out)}]({p.relative_to(out)})" for p in pngs), ""]
            lines += [f"![{p.stem}]({p.relative_to(out)})" for p in pngs[:4]] + [""]
    lines += ["## Config", "", "```yaml", config_yaml.rstrip(), "```", ""]
    return write_atomic(out / "summary.md", "\n".join(lines))
