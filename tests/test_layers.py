"""The package's layers: no import cycle between packages, no private name taken across them.

Every module of ``uvms_jax`` is parsed with :mod:`ast` (nothing is imported), and every import
statement in it, at module level or inside a function, becomes an edge between two *units*: a
subpackage (``uvms_jax.kin``) or a top-level module (``uvms_jax.files``). The graph of units
must be acyclic, and a unit may take from another only its public names (none starting with
``_``). docs/design.md's layer list must name the units in an order the graph allows.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "uvms_jax"
DESIGN = ROOT / "docs" / "design.md"


def _module_name(path: Path) -> str:
    """``uvms_jax/kin/_fk.py`` → ``uvms_jax.kin._fk``; a package's ``__init__`` is the package."""
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _unit(module: str) -> str | None:
    """The unit a dotted module name belongs to (``uvms_jax.kin._fk`` → ``kin``); None outside."""
    parts = module.split(".")
    if parts[0] != "uvms_jax" or len(parts) < 2:
        return None
    if not ((PACKAGE / parts[1]).is_dir() or (PACKAGE / f"{parts[1]}.py").is_file()):
        return None  # a name of the root package (``__version__``)
    return parts[1]


def _imports(path: Path) -> list[tuple[str, tuple[str, ...], int]]:
    """Every import in one file, as (absolute module, names taken from it, line)."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(alias.name, (), node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            names = tuple(alias.name for alias in node.names)
            if base == "uvms_jax":  # from uvms_jax import kin, files: one import per unit
                found += [(f"uvms_jax.{n}", (), node.lineno) for n in names]
            else:
                found.append((base, names, node.lineno))
    return found


def _private_step(module: str, names: tuple[str, ...]) -> str | None:
    """The first private part of an import across units (a ``_module`` or a ``_name``), or None."""
    for part in module.split(".")[2:]:
        if part.startswith("_"):
            return part
    return next((n for n in names if n.startswith("_")), None)


def import_graph() -> tuple[dict[str, set[str]], list[str]]:
    """The units' graph (unit → units it imports) and every private import across units."""
    graph: dict[str, set[str]] = {}
    private = []
    for path in sorted(PACKAGE.rglob("*.py")):
        unit = _unit(_module_name(path))
        if unit is None:  # uvms_jax/__init__.py imports nothing of its own
            continue
        graph.setdefault(unit, set())
        for module, names, line in _imports(path):
            other = _unit(module)
            if other is None or other == unit:
                continue
            graph[unit].add(other)
            step = _private_step(module, names)
            if step is not None:
                private.append(f"{path.relative_to(ROOT)}:{line} takes {step} from {module}")
    return graph, private


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components of ``graph``, each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    components = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            components.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return components


def test_no_import_cycle_between_packages():
    graph, _ = import_graph()
    cycles = [c for c in strongly_connected(graph) if len(c) > 1]
    assert not cycles, f"packages importing each other: {cycles}"


def test_no_private_import_across_packages():
    _, private = import_graph()
    assert not private, "private names taken across packages:\n" + "\n".join(private)


def design_layers() -> dict[str, int]:
    """docs/design.md's layer list: unit → its row, 0 at the top.

    The list is the fenced block of the section "## Layers"; a row starts with ``uvms_jax.<unit>``
    and may name more units of the same row as ``.other`` (the bottom row, the papers' modules);
    indented lines continue a row's description."""
    section = DESIGN.read_text().split("## Layers", 1)[1]
    block = section.split("```", 2)[1]
    rows: dict[str, int] = {}
    for line in block.splitlines():
        if not line.startswith("uvms_jax."):
            continue
        first, *rest = line.split()
        units = [first.split(".")[1]] + [t[1:] for t in rest if re.fullmatch(r"\.[a-z0-9_]+", t)]
        row = len(set(rows.values()))
        for unit in units:
            if (PACKAGE / unit).is_dir() or (PACKAGE / f"{unit}.py").is_file():
                rows.setdefault(unit, row)
    return rows


def test_design_layers_match_the_imports():
    graph, _ = import_graph()
    rows = design_layers()
    assert set(rows) == set(graph), f"design.md's layers name {sorted(set(rows) - set(graph))} and omit " \
                                    f"{sorted(set(graph) - set(rows))}"
    bottom = max(rows.values())
    upward = [f"{u} → {v}" for u, vs in graph.items() for v in vs
              if rows[v] < rows[u] or (rows[v] == rows[u] and rows[u] != bottom)]
    assert not upward, f"imports against docs/design.md's layers: {sorted(upward)}"
