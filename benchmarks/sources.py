"""Every number in the prose of README.md, BENCHMARKS.md and docs/ has a source (docs/design.md,
"Numbers and their sources").

A number is either inside a generated block of ``benchmarks/report.py`` or in a Markdown block
(a paragraph, a list item or a table) that carries a source marker:

- ``<!-- src: FILE KEY ... -->``: the figures come from FILE (a path from the repository root:
  a result file in ``benchmarks/results/``, ``docs/reproduction.json``, a config in
  ``configs/``, a module). For a JSON or YAML file each KEY is a dotted path into it
  (``runs.0.loss``) and must exist; where its value is a number, the block must print it, at
  its precision, as it is or scaled by one of :data:`SCALES` (``0.0123`` as ``1.23 %``).
  For any other file each KEY must occur in it.
- ``<!-- paper: D11|D16|T22 ITEM -->``: the figures are the paper's, ITEM names where (a table,
  equation or section).
- ``<!-- cite: WORK -->``: the figures are another published work's, WORK names it.
- ``<!-- def: WHAT -->``: the figures define something (a limit, a setting, a tolerance, a
  dimension of a model): they are not measured.

What is not a number: anything in fenced code, inline code, math (``$...$``), HTML comments,
link targets and headings; references (``[D16]``, ``Table 5.6``, ``eqs 5.1–5.12``,
``Figs 5–8 and 11–15``, ``§4``, ``issue 44``); versions (``jax 0.10.2``, ``CUDA 13``, any
``1.2.3``); years (1900–2099); digits glued to letters
(``H100``, ``float32``); sizes in names (``12-DOF``, ``2-core``, ``8-bit``); and one-digit
integers (counting words: ``6 × 6``, ``3 planners``).

Usage: ``python benchmarks/report.py --check`` runs :func:`unsourced` over
:data:`SOURCED_DOCUMENTS` (with the generated blocks) and fails naming each number without a
source.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: docs/reproduction.md and its pages (docs/reproduction/): written by experiments/papers.py from
#: its templates, whose ``{placeholders}`` it fills from docs/reproduction.json.
GENERATED_DOCUMENTS = (ROOT / "docs" / "reproduction.md", *sorted((ROOT / "docs" / "reproduction").glob("*.md")))
#: The documents whose prose numbers need a source; the generated ones are checked through their
#: templates.
SOURCED_DOCUMENTS = (ROOT / "README.md", ROOT / "BENCHMARKS.md",
                     *sorted(p for p in (ROOT / "docs").rglob("*.md") if p not in GENERATED_DOCUMENTS),
                     *sorted((ROOT / "experiments" / "papers_templates").glob("*.md")))
PAPERS = ("D11", "D16", "T22")
#: How a value may be printed: as it is, in per cent, in thousandths (ms, mm), in millionths
#: (µs) or in millions ("1.26 M").
SCALES = (1.0, 100.0, 1e3, 1e6, 1e-6)

MARKER = re.compile(r"<!--\s*(?P<kind>src|paper|cite|def):\s*(?P<body>.*?)\s*-->", re.S)
_GENERATED = re.compile(r"<!-- report:(?P<name>[a-z0-9_]+) -->\n.*?<!-- /report:(?P=name) -->", re.S)
_FENCE = re.compile(r"^\s*```.*?^\s*```[^\n]*$", re.S | re.M)
_INLINE_CODE = re.compile(r"`[^`\n]*`")
_SKIP = [_GENERATED, _FENCE, re.compile(r"<!--.*?-->", re.S), re.compile(r"\$\$.*?\$\$", re.S),
         re.compile(r"\$[^$\n]+\$"), _INLINE_CODE, re.compile(r"\]\([^)\s]*\)"),
         re.compile(r"https?://\S+"), re.compile(r"\{[a-z_0-9]+(?::[^}]*)?\}"),  # template placeholders
         re.compile(r"\[[A-Z]{1,4}\d*[^\]\n]*\]"),  # citations: [D16], [T22] Table 5.5, [MLS]
         re.compile(r"\b(?:jax|torch|CUDA|Python|OMPL|MuJoCo|OR-Tools|Numba|NumPy|numpy|jaxlib)\s+\d+(?:\.\d+)*"),
         re.compile(r"(?:\b(?:Tables?|Figs?\.?|Figures?|[Ee]qs?\.?|Sections?|Appendix|Algorithms?|Chapter|ch\.|"
                    r"steps?|issues?|PR|stage|Deliver)|§|#)\s*[A-Z]?\d+(?:\.\d+)*[a-z]?"
                    r"(?:\s*(?:[–,-]|and|to|or)\s*[A-Z]?\d+(?:\.\d+)*[a-z]?)*")]
_NUMBER = re.compile(r"(?<![\w.-])[−-]?\d+(?:[  ,]\d{3})*(?:\.\d+)?(?:e[−-]?\d+)?"
                     r"(?![\w])(?!\.\d)(?!-(?:DOF|core|bit)\b)")
_LIST_ITEM = re.compile(r"^\s*(?:[-*+]|\d+\.)\s")


def _blank(m: re.Match) -> str:
    return re.sub(r"[^\n]", " ", m.group(0))


def _blocks(text: str) -> list[tuple[int, list[str]]]:
    """The Markdown blocks of ``text``: (first line number, lines); a blank line ends a block, and a
    list item or a heading starts one."""
    blocks, current, start = [], [], 0
    for i, line in enumerate(text.split("\n"), 1):
        if not line.strip() or _LIST_ITEM.match(line) or line.lstrip().startswith("#"):
            if current:
                blocks.append((start, current))
            current, start = ([line], i) if line.strip() else ([], i + 1)
            if line.lstrip().startswith("#"):
                blocks.append((start, current))
                current = []
            continue
        if not current:
            start = i
        current.append(line)
    if current:
        blocks.append((start, current))
    return blocks


def numbers(line: str) -> list[str]:
    """The numbers of one prose line (with its skipped parts already blanked)."""
    if line.lstrip().startswith("#"):
        return []
    out = []
    for m in _NUMBER.finditer(line):
        token = m.group(0)
        digits = re.sub(r"\D", "", token.split("e")[0])
        if re.fullmatch(r"(19|20)\d\d", token) or (len(digits) == 1 and "." not in token and "e" not in token):
            continue
        out.append(token)
    return out


def _value(token: str) -> float:
    return float(token.replace("−", "-").replace(" ", "").replace(" ", "").replace(",", ""))


def _printed(value: float, tokens: list[str]) -> bool:
    """Whether one of ``tokens`` prints ``value`` (or 100× or 1000× it) at the token's precision."""
    for token in tokens:
        mantissa = token.split("e")[0]
        decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
        exponent = int(token.split("e")[1].replace("−", "-")) if "e" in token else 0
        half = 0.5 * 10.0 ** (exponent - decimals) * (1 + 1e-9)
        for scale in SCALES:
            if abs(abs(_value(token)) - abs(value * scale)) <= half:
                return True
    return False


def _resolve(path: Path, key: str):
    """The value at dotted ``key`` of a JSON/YAML file; KeyError naming it if there is none."""
    if path.suffix == ".json":
        node = json.loads(path.read_text(encoding="utf-8"))
    else:
        import yaml

        node = yaml.safe_load(path.read_text(encoding="utf-8"))
    parts = key.split(".")
    while parts:
        part = parts.pop(0)
        while isinstance(node, dict) and part not in node and parts:  # a key with dots: "reached_0.99"
            part += "." + parts.pop(0)
        if isinstance(node, list) and part.lstrip("-").isdigit():
            node = node[int(part)]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            raise KeyError(part)
    return node


def marker_errors(body: str, kind: str, tokens: list[str]) -> list[str]:
    """What is wrong with one marker of a block whose numbers are ``tokens``."""
    words = body.split()
    if kind in ("def", "cite"):
        return [] if words else [f"a {kind} marker names nothing"]
    if kind == "paper":
        return [] if words and words[0] in PAPERS and len(words) > 1 else [f"paper marker {body!r}: "
                                                                          f"give one of {PAPERS} and an item"]
    if not words:
        return ["a src marker names no file"]
    path = ROOT / words[0]
    if not path.is_file():
        return [f"src marker: no file {words[0]}"]
    if path.suffix not in (".json", ".yaml", ".yml"):
        text = path.read_text(encoding="utf-8")
        return [f"src marker: {k!r} not in {words[0]}" for k in words[1:] if k not in text]
    errors = []
    for key in words[1:]:
        try:
            value = _resolve(path, key)
        except (KeyError, IndexError):
            errors.append(f"src marker: no key {key} in {words[0]}")
            continue
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) \
                and not _printed(float(value), tokens):
            errors.append(f"src marker: {words[0]} {key} = {value:g} is not printed in its block")
    return errors


def unsourced(text: str) -> list[str]:
    """``line: problem`` for each number of ``text`` without a source and each bad marker."""
    plain = text
    for rx in _SKIP:
        plain = rx.sub(_blank, plain)
    plain_lines = plain.split("\n")
    coded = _INLINE_CODE.sub(_blank, _FENCE.sub(_blank, text)).split("\n")  # markers shown as code are none
    problems = []
    for start, lines in _blocks(text):
        raw = "\n".join(coded[start - 1:start - 1 + len(lines)])
        tokens = [(start + i, t) for i in range(len(lines)) for t in numbers(plain_lines[start - 1 + i])]
        markers = list(MARKER.finditer(raw))
        printed = [m.group(0) for i in range(len(lines)) for m in _NUMBER.finditer(plain_lines[start - 1 + i])]
        for m in markers:
            problems += [f"{start}: {e}" for e in marker_errors(m.group("body"), m.group("kind"), printed)]
        if not markers:
            problems += [f"{line}: {token!r} has no source" for line, token in tokens]
    return problems


def check(documents=SOURCED_DOCUMENTS) -> dict[str, list[str]]:
    """``{document: problems}`` for the documents with any."""
    found = {str(doc.relative_to(ROOT)): unsourced(doc.read_text(encoding="utf-8")) for doc in documents}
    return {name: p for name, p in found.items() if p}
