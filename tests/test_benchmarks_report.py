"""README.md, BENCHMARKS.md and docs/ quote their generated figures as written from benchmarks/results/
(benchmarks/report.py)."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("benchmarks_report", ROOT / "benchmarks" / "report.py")
report = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(report)


def test_every_generated_block_matches_its_result_files():
    texts = [doc.read_text() for doc in report.DOCUMENTS]
    names = [m.group("name") for text in texts for m in report.BLOCK.finditer(text)]
    assert sorted(names) == sorted(report.BLOCKS)  # every block is in a document, once
    for doc, text in zip(report.DOCUMENTS, texts):
        assert report.stale_blocks(text) == [], f"{doc.name}: run python benchmarks/report.py"


def test_an_edited_figure_is_caught():
    text = report.DOCUMENTS[1].read_text()
    block = next(report.BLOCK.finditer(text))
    edited = text[: block.start("body")] + block.group("body").replace("e", "E", 1) + text[block.end("body"):]
    assert report.stale_blocks(edited) == [block.group("name")]
