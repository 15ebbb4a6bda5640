"""README.md, BENCHMARKS.md with its pages (docs/benchmarks/) and docs/ quote their generated
figures as written from benchmarks/results/ (benchmarks/report.py)."""

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
        assert report.stale_blocks(text) == [], f"{doc.relative_to(ROOT)}: run python benchmarks/report.py"


def test_an_edited_figure_is_caught():
    text = report.DOCUMENTS[1].read_text()
    block = next(report.BLOCK.finditer(text))
    edited = text[: block.start("body")] + block.group("body").replace("e", "E", 1) + text[block.end("body"):]
    assert report.stale_blocks(edited) == [block.group("name")]


_spec_sources = importlib.util.spec_from_file_location("benchmarks_sources", ROOT / "benchmarks" / "sources.py")
sources = importlib.util.module_from_spec(_spec_sources)
_spec_sources.loader.exec_module(sources)


def test_every_prose_number_has_a_source():
    assert sources.check() == {}


def test_an_unsourced_number_is_caught():
    text = sources.SOURCED_DOCUMENTS[0].read_text()
    planted = text + "\nThe demo now runs in 12.5 s.\n"
    assert sources.unsourced(text) == []
    assert sources.unsourced(planted) == [f"{len(planted.splitlines())}: '12.5' has no source"]


def test_what_is_not_a_number():
    # references, citations, versions, years, names, code, math and counting words
    prose = ("See Tables 5.6–5.9, eqs 5.1–5.12, Figs 5–8 and 11–15, §4.2 and [D16] Table 4; jax 0.10.2 "
             "(2016) on an H100 in float32, a 12-DOF UVMS, `n = 6000`, $l_0 = 0.1$, 3 planners.\n")
    assert sources.unsourced(prose) == []


def test_a_marker_is_checked_against_its_file():
    good = "Loss 0.91 % at worst. <!-- src: benchmarks/results/docking_map_h100.json summary.loss_max -->\n"
    assert sources.unsourced(good) == []
    stale = good.replace("0.91 %", "0.95 %")
    assert "is not printed in its block" in sources.unsourced(stale)[0]
    missing = good.replace("summary.loss_max", "summary.no_such_key")
    assert "no key summary.no_such_key" in sources.unsourced(missing)[0]
    assert sources.unsourced("Settings 0.25 and 60. <!-- def: the controller's limits -->\n") == []
    assert sources.unsourced("Table 4 gives 21810. <!-- paper: D99 Table 4 -->\n") != []


#: Claims an audit found unsourced, misattributed or contradicted (issue 44), each fixed once:
#: none may come back into the prose.
RETRACTED = (
    "the paper's data size",  # [D16] gives no training-set size: 6000 is configs/surrogate.yaml's
    "the paper's: 0.20–0.50", "falls from 0.23 to 0.02",  # [D16]'s text gives no KCI values
    "124–128× were against",  # our ratios of the paper's one time per network type
    "-candidate grid's optimum",  # the CPU GA against a grid it beats, not the optimum
    "lie in the quarter nearest the start, as the paper's do",  # ours lie on its edges
    "M_a \\approx 0.18", "0.83–0.93", "0.05 m forward",  # theory.md against the record
    "1.4 GB", "2.9 GB", "24 µm", "56 µm", "450 times slower", "about 0.4 s after the signal",
    "of iterations improve on eq. 4.1",  # figures no result file backs
)


def test_retracted_claims_stay_out():
    for doc in sources.SOURCED_DOCUMENTS + sources.GENERATED_DOCUMENTS:
        text = doc.read_text()
        assert [c for c in RETRACTED if c in text] == [], doc.name
