"""Typed settings from plain mappings: the one bridge from configs to stage functions.

Every stage of the package takes a frozen dataclass of settings (plain values, nested
dataclasses, tuples). Experiments turn a Hydra config into a ``dict``
(``OmegaConf.to_container(cfg, resolve=True)``) and call :func:`from_mapping`; library code
never sees a ``DictConfig``.

>>> @dataclasses.dataclass(frozen=True)
... class Grid:
...     counts: tuple[int, ...] = (3, 3)
...     chunk_size: int = 1024
>>> from_mapping(Grid, {"counts": [4, 5]})
Grid(counts=(4, 5), chunk_size=1024)

A field declared with :func:`setting` carries its allowed values (a range, a list of choices,
an existing file); :func:`from_mapping` checks them and names the key path as the config writes
it, every bad key of a mapping in one message:

>>> @dataclasses.dataclass(frozen=True)
... class GA:
...     mutation_rate: float = setting(0.08, ge=0, le=1)
...     population_size: int = setting(60, ge=1)
>>> from_mapping(GA, {"mutation_rate": 2.0, "population_size": -8}, "ga")
Traceback (most recent call last):
...
uvms_jax.settings.SettingsError: ga.mutation_rate: expected a value in [0, 1], got 2.0; \
ga.population_size: expected a value >= 1, got -8
"""

from __future__ import annotations

import dataclasses
import math
import os
import types
import typing
from collections.abc import Mapping
from typing import Any, TypeVar

import yaml

__all__ = ["MAX_YAML_BYTES", "MAX_YAML_DEPTH", "MAX_YAML_NODES", "Check", "SettingsError", "bounded_yaml_loader",
           "check_fields", "check_keys", "from_mapping", "load_yaml", "read_yaml", "setting"]

T = TypeVar("T")

# The most nodes a YAML document may hold with every alias expanded: a settings file has a few
# hundred; an alias bomb (nested anchors, each repeating the one before) has billions and would
# fill the memory of whatever expands it (a config library copying every alias).
MAX_YAML_NODES = 100_000
MAX_YAML_DEPTH = 64  # nested mappings and lists (a settings file has < 10; far below Python's recursion limit)
# The largest YAML document read: a settings file or an arm card has a few kB, the largest plan
# file (a JointTrajectory within MAX_YAML_NODES values) about 1 MB; PyYAML's safe loader reads
# about 1 MB/s on a shared 2-core CPU, so no document takes more than a few seconds.
MAX_YAML_BYTES = 4 << 20


class SettingsError(ValueError):
    """A settings mapping that does not fit its dataclass; the message names the key."""


@dataclasses.dataclass(frozen=True)
class Check:
    """Allowed values of one setting (in a field's metadata, see :func:`setting`).

    A list or tuple value is checked element by element, ``None`` (an optional setting left
    unset) always passes.

    Attributes:
      ge, gt, le, lt: bounds (``>=``, ``>``, ``<=``, ``<``) of a number.
      choices: the allowed values (e.g. names of dtypes), or a mapping whose keys are (a
        registry such as the scheduling solvers: read when checked, so names added later count).
      file: the value is the path of an existing file (relative: to the working directory);
        with ``choices``, one of those or an existing file.
    """

    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    lt: float | None = None
    choices: tuple[Any, ...] | Mapping[Any, Any] | None = None
    file: bool = False

    def allowed(self) -> str:
        """The allowed values in words, e.g. ``"a value in [0, 1]"``."""
        if self.choices is not None and self.file:
            return f"one of {list(self.choices)} or an existing file"
        if self.choices is not None:
            return f"one of {list(self.choices)}"
        if self.file:
            return "an existing file"
        lo = f"[{self.ge:g}" if self.ge is not None else f"({self.gt:g}" if self.gt is not None else None
        hi = f"{self.le:g}]" if self.le is not None else f"{self.lt:g})" if self.lt is not None else None
        if lo and hi:
            return f"a value in {lo}, {hi}"
        if lo:
            return f"a value {'>=' if lo[0] == '[' else '>'} {lo[1:]}"
        if hi:
            return f"a value {'<=' if hi[-1] == ']' else '<'} {hi[:-1]}"
        return "any value"

    def ok(self, value: Any) -> bool:
        """Whether one (non-list) value is allowed."""
        if self.choices is not None and value in self.choices:
            return True
        if self.file:
            return isinstance(value, (str, os.PathLike)) and os.path.isfile(value)
        if self.choices is not None:
            return False
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return True  # not a number: the type check has the say
        return not ((self.ge is not None and not value >= self.ge) or (self.gt is not None and not value > self.gt)
                    or (self.le is not None and not value <= self.le) or (self.lt is not None and not value < self.lt))

    def problems(self, value: Any, where: str) -> list[str]:
        """One message per value (or list element) not allowed, naming its key path."""
        if value is None:
            return []
        if isinstance(value, (list, tuple)):
            bad = [v for v in value if v is not None and not isinstance(v, (list, tuple)) and not self.ok(v)]
            if len(bad) > 1:  # e.g. grid.counts: [0, 0, 0, 0]
                return [f"{where}: expected each {self.allowed()}, got {list(value)!r}"]
            return [m for i, v in enumerate(value) for m in self.problems(v, f"{where}[{i}]")]
        if self.ok(value):
            return []
        if self.file and self.choices is None and isinstance(value, (str, os.PathLike)):
            relative = "" if os.path.isabs(value) else f" (relative to the working directory {os.getcwd()})"
            return [f"{where}: no such file {os.fspath(value)!r}{relative}"]
        return [f"{where}: expected {self.allowed()}, got {value!r}"]


def setting(default: Any = dataclasses.MISSING, *, default_factory: Any = dataclasses.MISSING,
            ge: float | None = None, gt: float | None = None, le: float | None = None, lt: float | None = None,
            choices: tuple[Any, ...] | Mapping[Any, Any] | None = None, file: bool = False) -> Any:
    """A dataclass field whose allowed values :func:`from_mapping` checks (see :class:`Check`).

    >>> @dataclasses.dataclass(frozen=True)
    ... class Solvers:
    ...     names: tuple[str, ...] = setting(("greedy",), choices=("greedy", "exact"))
    >>> from_mapping(Solvers, {"names": ["greedy", "bogus"]}, "sched")
    Traceback (most recent call last):
    ...
    uvms_jax.settings.SettingsError: sched.names[1]: expected one of ['greedy', 'exact'], got 'bogus'
    """
    # A mapping stays live (a registry: names added later are allowed too).
    live = choices is None or isinstance(choices, Mapping)
    check = Check(ge=ge, gt=gt, le=le, lt=lt, choices=choices if live else tuple(choices), file=file)
    return dataclasses.field(default=default, default_factory=default_factory, metadata={"check": check})


def check_fields(settings: Any) -> None:
    """Raise :class:`SettingsError` naming every field of the dataclass instance ``settings``
    whose value its :func:`setting` check refuses: the same check :func:`from_mapping` makes,
    for settings built directly (call it from ``__post_init__``)."""
    name = type(settings).__name__
    problems = [m for f in dataclasses.fields(settings) if "check" in f.metadata
                for m in f.metadata["check"].problems(getattr(settings, f.name), f"{name}.{f.name}")]
    if problems:
        raise SettingsError("; ".join(problems))


def parameters(cls: type[T], settings: Any, **given: Any) -> T:
    """An instance of the dataclass ``cls`` with each field taken from the same-named attribute
    of ``settings``, apart from those ``given`` (values the settings do not hold): the one
    mapping from a stage's settings to its static and traced parameters.

    Raises:
      TypeError: a field of ``cls`` that is neither in ``settings`` nor given (a renamed setting
        must not fall back to a default without a word).
    """
    names = [f.name for f in dataclasses.fields(cls) if f.init and f.name not in given]
    missing = [n for n in names if not hasattr(settings, n)]
    if missing:
        raise TypeError(f"{type(settings).__name__} has no {missing} for {cls.__name__}")
    return cls(**given, **{n: getattr(settings, n) for n in names})


def check_keys(mapping: Mapping[str, Any], known: Any, where: str = "") -> None:
    """Raise :class:`SettingsError` naming the keys of ``mapping`` (at key path ``where``; ``""``:
    the top level of a config) that are not in ``known``.

    >>> check_keys({"seed": 0, "foo": 1}, ["seed", "stages"])
    Traceback (most recent call last):
    ...
    uvms_jax.settings.SettingsError: foo: unknown key; known: ['seed', 'stages']
    """
    unknown = sorted(set(mapping) - set(known), key=str)
    if not unknown:
        return
    if where:
        raise SettingsError(f"{where}: unknown keys {unknown}; known: {sorted(known)}")
    raise SettingsError(f"{', '.join(map(str, unknown))}: unknown key{'s' if len(unknown) > 1 else ''}; "
                        f"known: {sorted(known)}")


def _kind(tp: Any) -> str:
    """A type in words, for a value that fits none of a union's alternatives."""
    origin = typing.get_origin(tp)
    if dataclasses.is_dataclass(tp) or origin in (dict, Mapping) or tp in (dict, Mapping):
        return "a mapping"
    if origin is tuple:
        return "a list"
    words = {bool: "true/false", int: "an integer", float: "a number", str: "a string"}
    return words.get(tp, getattr(tp, "__name__", str(tp)))


def _convert(tp: Any, value: Any, where: str) -> Any:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if tp is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        alternatives = [a for a in args if a is not type(None)]
        nested = [a for a in alternatives if dataclasses.is_dataclass(a)]
        if isinstance(value, Mapping) and nested:  # a mapping for a dataclass: its own errors, by key
            alternatives = nested
        for a in alternatives:
            try:
                return _convert(a, value, where)
            except SettingsError as e:
                errors.append(str(e))
        raise SettingsError(errors[0] if len(errors) == 1 else
                            f"{where}: expected {' or '.join(map(_kind, alternatives))}, got {value!r}")
    if dataclasses.is_dataclass(tp):
        if isinstance(value, tp):
            return value
        return from_mapping(tp, value, where)
    if origin is tuple:
        if not isinstance(value, (list, tuple)):
            raise SettingsError(f"{where}: expected a list, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(args[0], v, f"{where}[{i}]") for i, v in enumerate(value))
        if args and len(args) != len(value):
            raise SettingsError(f"{where}: expected {len(args)} values, got {len(value)}")
        return tuple(_convert(a, v, f"{where}[{i}]") for i, (a, v) in enumerate(zip(args, value))) if args else tuple(value)
    if origin in (dict, Mapping) or tp in (dict, Mapping):
        if not isinstance(value, Mapping):
            raise SettingsError(f"{where}: expected a mapping, got {value!r}")
        kt, vt = args if args else (Any, Any)
        return {_convert(kt, k, f"{where} key"): _convert(vt, v, f"{where}.{k}") for k, v in value.items()}
    if origin is typing.Literal:
        if value not in args:
            raise SettingsError(f"{where}: {value!r} is not one of {list(args)}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise SettingsError(f"{where}: expected true/false, got {value!r}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise SettingsError(f"{where}: expected an integer, got {value!r}")
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SettingsError(f"{where}: expected a number, got {value!r}")
        if not math.isfinite(value):  # no setting means "unbounded" by inf, or anything by NaN
            raise SettingsError(f"{where}: expected a finite number, got {value!r}")
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise SettingsError(f"{where}: expected a string, got {value!r}")
        return value
    return value


def from_mapping(cls: type[T], mapping: Mapping[str, Any] | None, where: str = "") -> T:
    """``cls`` (a dataclass) built from ``mapping``, converting nested mappings and lists.

    Keys absent from ``mapping`` take the dataclass defaults; unknown keys, missing required
    keys, values of the wrong type (a float setting takes finite numbers only: never NaN or inf), values outside a field's :class:`Check` (:func:`setting`)
    and values that the dataclass's ``__post_init__`` rejects (``ValueError``) raise
    :class:`SettingsError` naming the key path (``where`` is the mapping's own, e.g. ``ga``).
    Every bad key of the mapping (and of its nested mappings) is named, in one message.
    """
    if mapping is None:
        mapping = {}
    if not isinstance(mapping, Mapping):
        raise SettingsError(f"{where or cls.__name__}: expected a mapping, got {mapping!r}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    check_keys(mapping, fields, where or cls.__name__)
    kwargs, errors = {}, []
    for k, f in fields.items():
        if k not in mapping and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            errors.append(f"{where}.{k}: missing (required)" if where else f"{k}: missing (required)")
    for k, v in mapping.items():
        path = f"{where}.{k}" if where else k
        try:
            kwargs[k] = _convert(hints[k], v, path)
        except SettingsError as e:
            errors.append(str(e))
            continue
        check = fields[k].metadata.get("check")
        if check is not None:
            errors += check.problems(kwargs[k], path)
    if errors:
        raise SettingsError("; ".join(errors))
    try:
        return cls(**kwargs)
    except SettingsError:
        raise
    except (TypeError, ValueError) as e:  # missing keys; checks of the dataclass's __post_init__
        raise SettingsError(f"{where or cls.__name__}: {e}") from e


def _expanded_nodes(node: yaml.Node, memo: dict[int, int]) -> int:
    """Nodes of ``node``'s tree with every alias expanded (an alias is the anchored node itself,
    counted once per use, computed once: linear in the document); ``inf`` for an alias inside
    its own anchor (a recursive document, endless when expanded)."""
    if id(node) not in memo:
        memo[id(node)] = math.inf  # met again before it is counted: an alias inside its own anchor
        children = [c for pair in node.value for c in pair] if isinstance(node, yaml.MappingNode) else \
            node.value if isinstance(node, yaml.SequenceNode) else []
        memo[id(node)] = 1 + sum(_expanded_nodes(c, memo) for c in children)
    return memo[id(node)]


def bounded_yaml_loader(base: type = yaml.SafeLoader) -> type:
    """A subclass of the YAML loader ``base`` (a ``yaml.SafeLoader``) that refuses a document
    holding more than :data:`MAX_YAML_NODES` nodes with its aliases expanded (an alias bomb) and
    a mapping with a repeated key (the last one would win without a word) and nesting deeper than
    :data:`MAX_YAML_DEPTH`; each raises ``yaml.YAMLError`` naming the line, before anything is
    built from the document."""

    class BoundedLoader(base):
        depth = 0

        def __init__(self, stream):
            size = _stream_bytes(stream)
            if size > MAX_YAML_BYTES:
                raise yaml.YAMLError(f"{getattr(stream, 'name', '<text>')}: {size} bytes of YAML, more than the "
                                     f"{MAX_YAML_BYTES} allowed")
            super().__init__(stream)

        def compose_node(self, parent, index):
            self.depth += 1
            try:
                if self.depth > MAX_YAML_DEPTH:
                    raise yaml.composer.ComposerError(None, None, f"nested deeper than {MAX_YAML_DEPTH} levels",
                                                      self.peek_event().start_mark)
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1

        def compose_document(self):
            node = super().compose_document()
            if node is not None and _expanded_nodes(node, {}) > MAX_YAML_NODES:
                raise yaml.composer.ComposerError(
                    None, None, f"with its aliases expanded, the document holds more than {MAX_YAML_NODES} values "
                    "or an alias inside its own anchor; write it without nested aliases", node.start_mark)
            return node

        def construct_mapping(self, node, deep=False):
            seen = set()
            for key_node, _ in node.value:
                key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
                if key is not None and key in seen:
                    raise yaml.constructor.ConstructorError(None, None, f"found duplicate key {key!r}",
                                                            key_node.start_mark)
                seen.add(key)
            return super().construct_mapping(node, deep=deep)

    return BoundedLoader


def _stream_bytes(stream: Any) -> int:
    """The size of a YAML stream [bytes]: a string's, a file's (0 for another stream)."""
    if isinstance(stream, str):
        return len(stream.encode("utf-8", "surrogatepass"))
    if isinstance(stream, bytes):
        return len(stream)
    try:
        return os.fstat(stream.fileno()).st_size
    except (AttributeError, OSError, ValueError):  # io.StringIO and the like: in memory already
        return 0


def load_yaml(text: str) -> Any:
    """``text`` as YAML with the safe loader, bounded (:func:`bounded_yaml_loader`; at most
    :data:`MAX_YAML_BYTES`): the package's one way to read YAML.

    Raises:
      yaml.YAMLError: malformed YAML, a repeated key, an alias bomb, nesting too deep (naming
        the line), or too long a text.
    """
    return yaml.load(text, Loader=_LOADER)  # noqa: S506  (a SafeLoader subclass)


def read_yaml(path: str | os.PathLike, what: str = "") -> Any:
    """The YAML file at ``path``, read with :func:`load_yaml` (``None`` for an empty file).

    Raises:
      SettingsError: (a ValueError) an unreadable file, a file larger than
        :data:`MAX_YAML_BYTES`, or every refusal of :func:`load_yaml`; one line naming
        ``what`` (e.g. ``"arm card"``), the file and the line.
    """
    name = f"{what} {os.fspath(path)}" if what else os.fspath(path)
    try:
        size = os.stat(path).st_size
        if size > MAX_YAML_BYTES:
            raise SettingsError(f"{name}: {size} bytes of YAML, more than the {MAX_YAML_BYTES} allowed")
        with open(path, encoding="utf-8") as f:
            text = f.read()
        return load_yaml(text)
    except OSError as e:
        raise SettingsError(f"{name}: cannot read it ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise SettingsError(f"{name}: not UTF-8 text ({e.reason} at byte {e.start})") from None
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        line = f", line {mark.line + 1}" if mark is not None else ""
        raise SettingsError(f"{name}{line}: {' '.join(str(e.problem or e.context).split())}") from None
    except yaml.YAMLError as e:
        raise SettingsError(f"{name}: {' '.join(str(e).split())}") from None


_LOADER = bounded_yaml_loader()
