"""The quoted figures of README.md, BENCHMARKS.md (with its pages, docs/benchmarks/) and docs/
(theory, docking, hover, planning), generated from benchmarks/results/ and docs/reproduction.json.

Each generated block sits between ``<!-- report:NAME -->`` and ``<!-- /report:NAME -->`` in one
of :data:`DOCUMENTS`, and is written by the function of that name in ``benchmarks/blocks/`` (one
module per topic, :data:`BLOCKS`) from the JSON files
that the benchmark scripts print or a pipeline run writes (``results.json`` of ``make demo``,
copied as ``demo_cpu.json``; the command that wrote a file is named next to its block). So a
figure in a block always has a file and a command behind it, and
``tests/test_benchmarks_report.py`` fails when a block no longer matches its files.

Every other number in the prose of these documents carries a source marker
(``benchmarks/sources.py``; docs/design.md, "Numbers and their sources").

Usage: python benchmarks/report.py            # rewrite the blocks
       python benchmarks/report.py --check    # exit 1 naming the blocks that are out of date
                                              # and the prose numbers without a source
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # blocks/ and sources.py, also when imported by path
from blocks import docking, hover, kin, planning, runs, surrogate  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOCUMENTS = (ROOT / "README.md", ROOT / "BENCHMARKS.md", *sorted((ROOT / "docs" / "benchmarks").glob("*.md")),
             ROOT / "docs" / "theory.md", ROOT / "docs" / "docking.md", ROOT / "docs" / "hover.md", ROOT / "docs" / "hover_batch.md",
             ROOT / "docs" / "planning.md")
BLOCK = re.compile(r"(<!-- report:(?P<name>[a-z0-9_]+) -->\n)(?P<body>.*?)(<!-- /report:(?P=name) -->)", re.S)
#: block name → its renderer (``() -> str``), from every topic module's ``__all__``.
BLOCKS = {name: getattr(module, name) for module in (kin, docking, surrogate, hover, planning, runs)
          for name in module.__all__}


def render(text: str) -> str:
    """``text`` (a document) with every report block regenerated from its files."""
    def block(m: re.Match) -> str:
        name = m.group("name")
        if name not in BLOCKS:
            raise KeyError(f"a document has a block {name!r} that benchmarks/report.py does not write")
        return m.group(1) + BLOCKS[name]() + m.group(4)
    return BLOCK.sub(block, text)


def stale_blocks(text: str) -> list[str]:
    """Names of the blocks of ``text`` that differ from what their files give."""
    fresh = render(text)
    old = {m.group("name"): m.group("body") for m in BLOCK.finditer(text)}
    new = {m.group("name"): m.group("body") for m in BLOCK.finditer(fresh)}
    return [name for name in old if old[name] != new[name]]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="only report blocks that are out of date and prose numbers without a source")
    args = parser.parse_args()
    stale = {doc.relative_to(ROOT).as_posix(): stale_blocks(doc.read_text()) for doc in DOCUMENTS}
    if args.check:
        import sources

        stale = {name: blocks for name, blocks in stale.items() if blocks}
        if stale:
            print(f"blocks out of date with benchmarks/results: {stale}", file=sys.stderr)
        unsourced = sources.check()
        for name, problems in unsourced.items():
            print("\n".join(f"{name}:{p}" for p in problems), file=sys.stderr)
        return 1 if stale or unsourced else 0
    for doc in DOCUMENTS:
        doc.write_text(render(doc.read_text()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
