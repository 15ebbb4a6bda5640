"""Regenerate docs/reproduction.md and its pages, one per paper (docs/reproduction/): every table
and figure of the three papers, theirs beside ours.

    python experiments/papers.py                    # preset "fast": 10–25 min on a 2-core CPU
    python experiments/papers.py --preset paper     # the papers' sizes where they differ
    python experiments/papers.py --out /tmp/repro   # write elsewhere (docs + img/papers/)
    python experiments/papers.py --only docking --preset paper   # one section again, the others kept

Four sections, each computed by the package and written into its Markdown template
(experiments/papers_templates/<section>.md, ``{placeholders}`` for the numbers), on the page of
its paper (:data:`PAGES`):

- docking paper [D11] (uvms_jax.papers.docking): Tables 3–4 under our frames, the bound on w of
  any 6 × 6 Jacobian of the arm, M_a under the readings of the paper we tried, headings against
  the bearing to the task centre, and the w_max maps of Figs 9–10;
- its arm drawn (uvms_jax.papers.docking_views, ``docking_views``: a minute or two on a CPU):
  the arm at K, L, M, N in 3-D and from the side (Figs 5–8, 12–15) and the final pose on the
  block (Fig. 11), at the paper's run 1 and at our optimum;
- dexterity paper [D16] (uvms_jax.papers.dexterity): Tables 3–5 for the paper's Jacobian form
  (spatial, eq. 6) and ours (geometric), FFBN/RBFN designed with the paper's loops, speed-ups
  against the project's fastest analytic path;
- thesis [T22] (uvms_jax.papers.thesis): Tables 5.2–5.4 per planner on the thesis cage planned
  here with RRTConnect, BKPIECE1 and PRM (or on a saved edges.csv, ``--edges``), Table 5.5 on our
  RRTConnect instance and on the eq. 4.1 matrix, GRASP cost and time against iterations
  (Figs 5.9–5.12) with the thesis's local search and ours, Fig. 5.8, and the weight-scenario
  tables (5.6–5.9, A.1–A.5) on our RRTConnect instance.

Figures go to ``<out>/img/papers/``. Everything the papers print is written once, as data, in
uvms_jax.papers (``D11_*``, ``D16_*``, ``T22_*``); the fixed prose is in the templates. Every
computed field goes to ``<out>/reproduction.json`` beside the documents, which are exactly
:func:`documents` of those fields (``tests/papers`` renders it again and compares): the one source
of every number the document quotes. Each section records the command, preset and device of
its own run, so ``--only`` recomputes some sections (a GPU for the docking paper's sizes, say)
and keeps the others as they were recorded.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import sys
import time
from pathlib import Path

import jax

from uvms_jax.files import write_atomic, write_json
from uvms_jax.papers import PRESETS

log = logging.getLogger("papers")
ROOT = Path(__file__).resolve().parents[1]
TEMPLATES = Path(__file__).resolve().parent / "papers_templates"
RESULTS = ROOT / "benchmarks" / "results"
SECTIONS = ("docking", "docking_views", "surrogate", "thesis")
#: The FFBN-KCI size search at our training-set size that the [D16] section quotes
#: (`benchmarks/surrogate_sizes.py`; too slow for a CPU run of this script).
SIZE_SEARCH = ROOT / "benchmarks" / "results" / "surrogate_ffbn_kci_sizes_gpu.json"


def render(name: str, **fields) -> str:
    """The template ``papers_templates/<name>.md`` with its ``{placeholders}`` filled from ``fields``."""
    return (TEMPLATES / f"{name}.md").read_text(encoding="utf-8").format(**fields)


TEMPLATE_OF = {"docking": "docking", "docking_views": "docking_views", "surrogate": "dexterity", "thesis": "thesis"}
#: The papers' pages, in docs/reproduction/: page → the sections it holds, in order.
PAGES = {"docking": ("docking", "docking_views"), "dexterity": ("surrogate",), "thesis": ("thesis",)}
PAGE_DIR = "reproduction"
PAGE_HEAD = ("One paper's part of [Reproducing the papers](../reproduction.md), which says how to run it,\n"
             "lists every item of the three papers and names the runs that computed this page.\n\n")
INDEX_HEADING = "## 1–3. The papers, one page each\n\n"


def fields_of(name: str, preset, img: Path, edges: Path | None) -> dict:
    """The computed fields of one section (``name`` of :data:`SECTIONS`)."""
    from uvms_jax.papers import dexterity, docking, docking_views, thesis

    if name == "docking":
        return docking.docking_fields(preset, img)
    if name == "docking_views":
        return docking_views.view_fields(preset, img)
    if name == "surrogate":
        return {**dexterity.dexterity_fields(preset, img), **size_search_fields()}
    return thesis.thesis_fields(preset, img, edges, ROOT / "configs")


def size_search_fields() -> dict:
    """The [D16] section's fields of :data:`SIZE_SEARCH`, read now (tests/papers compares them
    with the record, so the document follows the file)."""
    from uvms_jax.papers import dexterity

    record = json.loads(SIZE_SEARCH.read_text(encoding="utf-8"))
    return dexterity.size_search_fields(record, SIZE_SEARCH.relative_to(ROOT).as_posix())


def documents(record: dict) -> dict[str, str]:
    """reproduction.md and one page per paper (:data:`PAGES`), by their paths relative to the
    output folder, from the record of their runs: ``{"sections": {name: fields}}``, each
    section's fields holding the ``command``, ``preset`` and ``device`` of the run that computed it.

    reproduction.md holds what is not one paper's: how to run, an index of the pages, the
    execution on the Bravo 7, every item of the papers and the runs that computed them."""
    extra = {"surrogate": {"window_sweep": window_sweep()}}
    sections = {name: render(TEMPLATE_OF[name], **fields, **extra.get(name, {}))
                for name, fields in record["sections"].items()}
    pages = {f"{PAGE_DIR}/{page}.md": _page("\n".join(sections[n] for n in names))
             for page, names in PAGES.items() if all(n in sections for n in names)}
    index = "".join(f"- [{_heading(text)}]({path})\n" for path, text in pages.items())
    runs = sorted({(f["command"], f["device"]) for f in record["sections"].values()})
    footer = "\n---\nGenerated section by section: " + "; ".join(f"`{c}` on {d}" for c, d in runs) + ".\n"
    main = (render("intro") + render("howto") + INDEX_HEADING + index + "\n" + render("execution") + "\n"
            + render("items", t22_times=scenario_times()) + footer)
    return {"reproduction.md": main, **pages}


def _page(body: str) -> str:
    """One paper's page: a line back to reproduction.md, then its sections; the page sits one
    folder below docs/, so its figure links (``img/papers/…``, relative to docs/) go up one."""
    return PAGE_HEAD + body.replace("](img/", "](../img/")


def _heading(text: str) -> str:
    """The first second-level heading of a page (its paper's section title)."""
    return next(line[3:] for line in text.splitlines() if line.startswith("## "))


def scenario_times() -> str:
    """The execution-time column of [T22] Tables 5.6–5.9, as the thesis prints it, one row per table."""
    from uvms_jax.papers import T22_TABLES

    names = [row[0] for row in T22_TABLES["5.6"]]
    rows = ["| table | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    rows += [f"| {t} | " + " | ".join(f"{row[-1]:g}" for row in T22_TABLES[t]) + " |"
             for t in ("5.6", "5.7", "5.8", "5.9")]
    return "\n".join(rows)


def window_sweep() -> str:
    """The [D16] sampling-window sweep (``benchmarks/surrogate_window.py``) as a paragraph and a
    table: per setting, each network's units and largest relative test error (``*``: the 2 %
    goal met), from the last result file by name; empty text where there is none."""
    files = sorted(RESULTS.glob("surrogate_window_*.json"))
    if not files:
        return ""
    d = json.loads(files[-1].read_text(encoding="utf-8"))
    nets = ("ffbn_w", "ffbn_kci", "rbfn_w", "rbfn_kci")
    paper = " / ".join(str(d["paper"][n]["units"]) for n in nets)

    def cell(net):
        return "—" if net is None else f"{net['units']} ({100 * net['max_rel_test_error']:.1f} %{'*' if net['met_goal'] else ''})"

    rows = ["| sampling (ours unless named) | FFBN-w | FFBN-KCI | RBFN-w | RBFN-KCI |", "|---|---|---|---|---|"]
    rows += [f"| {s['name']} | " + " | ".join(cell(s["networks"].get(n)) for n in nets) + " |" for s in d["settings"]]
    command = d["command"].split(" --out ")[0]
    match, done = d["summary"]["all_networks_match"], d["summary"]["settings_done"]
    single = sorted({f"{n} ({s['name']})" for s in d["settings"] for n, net in s["networks"].items() if net["matches_paper"]})
    verdict = (f"{len(match) or 'None'} of the {done} settings reproduce{'s' if not match else ''} the paper's four sizes "
               f"({paper} units at 2 %) together{': ' + ', '.join(match) if match else ''}; single networks that match: "
               f"{', '.join(single) or 'none'}. The nearest in unit counts is \"{d['summary']['nearest']['name']}\"")
    return (f"**The sampling window, swept.** `{command}` on {d['device']} (`{files[-1].relative_to(ROOT).as_posix()}`; "
            f"unit caps FFBN {d['ffbn_max']}, RBFN {d['rbfn_max']}; a network matches the paper's when it meets the "
            f"2 % goal within {100 * d['match_tolerance']:.0f} % of its unit count). {verdict}. Units (largest "
            "relative test error; * goal met):\n\n"
            + "\n".join(rows) + "\n")


def device_name() -> str:
    """The device a section ran on, as the document names it: the GPU's name, or the CPU's cores."""
    d = jax.devices()[0]
    return d.device_kind if d.platform == "gpu" else f"{os.cpu_count()} {platform.machine()} CPU cores"


def recorded_sections(path: Path) -> dict:
    """The sections of an earlier run's ``reproduction.json`` (none if there is no such file)."""
    return json.loads(path.read_text(encoding="utf-8"))["sections"] if path.exists() else {}


def _plain(value):
    """A field as JSON holds it (NumPy scalars as Python numbers)."""
    return value.item() if hasattr(value, "item") else value


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="presets: " + "; ".join(f"{k}: {v}" for k, v in PRESETS.items()))
    ap.add_argument("--preset", choices=sorted(PRESETS), default="fast",
                    help="sizes (fast: 10 min on a 2-core CPU with a warm compilation cache, ~25 min cold; "
                         "paper: the papers' sizes, hours; tiny: a smoke run)")
    ap.add_argument("--out", type=Path, default=ROOT / "docs", help="folder of reproduction.md, reproduction/ and img/papers/")
    ap.add_argument("--edges", type=Path, default=None,
                    help="edges.csv of experiments/plan.py for the thesis tables (default: plan the thesis cage here)")
    ap.add_argument("--only", nargs="+", choices=SECTIONS, default=SECTIONS, help="sections to compute")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    logging.getLogger("jax").setLevel(logging.WARNING)
    jax.config.update("jax_enable_x64", True)  # float64 datasets and training of the surrogates
    p, img = PRESETS[args.preset], args.out / "img" / "papers"
    # What was computed, and how; not where it was written.
    command = " ".join(["python experiments/papers.py", f"--preset {p.name}",
                        *([f"--only {' '.join(args.only)}"] if tuple(args.only) != SECTIONS else []),
                        *([f"--edges {args.edges}"] if args.edges is not None else [])])
    # Sections not computed now keep their recorded run; a section missing from both is an error.
    sections = recorded_sections(args.out / "reproduction.json")
    missing = [n for n in SECTIONS if n not in args.only and n not in sections]
    if missing:
        ap.error(f"--only leaves out {', '.join(missing)}, which {args.out / 'reproduction.json'} does not hold")
    t0 = time.perf_counter()
    for name in args.only:
        t = time.perf_counter()
        fields = {k: _plain(v) for k, v in fields_of(name, p, img, args.edges).items()}
        sections[name] = fields | {"command": command, "device": device_name()}
        log.info("%s section in %.0f s", name, time.perf_counter() - t)
    total = time.perf_counter() - t0
    record = {"sections": {n: sections[n] for n in SECTIONS}}
    write_json(args.out / "reproduction.json", record, ensure_ascii=False)
    for path, text in documents(record).items():
        (args.out / path).parent.mkdir(parents=True, exist_ok=True)
        write_atomic(args.out / path, text)
    log.info("wrote %s and its pages in %s in %.0f s", args.out / "reproduction.md", args.out / PAGE_DIR, total)
    return 0


if __name__ == "__main__":
    sys.exit(main())
