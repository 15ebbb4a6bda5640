"""uvms_jax.settings: allowed values of settings (ranges, choices, files) checked by
from_mapping, every bad key named by its path in one message; the shipped defaults allowed."""

import dataclasses

import pytest

from uvms_jax import evo, pipeline, sched, surrogate
from uvms_jax.settings import SettingsError, check_keys, from_mapping, read_yaml, setting


@dataclasses.dataclass(frozen=True)
class Inner:
    rate: float = setting(0.5, ge=0, le=1)
    counts: tuple[int, ...] = setting((2, 2), ge=1)
    chunk: int | None = setting(None, gt=0)


@dataclasses.dataclass(frozen=True)
class Outer:
    inner: Inner = Inner()
    names: tuple[str, ...] = setting(("a",), choices=("a", "b"))
    matrix: str = setting("builtin", choices=("builtin",), file=True)
    path: str | None = setting(None, file=True)
    either: str | Inner | None = None


@pytest.mark.parametrize(("mapping", "message"), [
    ({"inner": {"rate": 1.5}}, "x.inner.rate: expected a value in [0, 1], got 1.5"),
    ({"inner": {"counts": [1, 0]}}, "x.inner.counts[1]: expected a value >= 1, got 0"),
    ({"inner": {"counts": [0, 0]}}, "x.inner.counts: expected each a value >= 1, got [0, 0]"),
    ({"inner": {"chunk": 0}}, "x.inner.chunk: expected a value > 0, got 0"),
    ({"names": ["a", "c"]}, "x.names[1]: expected one of ['a', 'b'], got 'c'"),
    ({"matrix": "nope.csv"}, "x.matrix: expected one of ['builtin'] or an existing file, got 'nope.csv'"),
    ({"path": "nope.csv"}, "x.path: no such file 'nope.csv' (relative to the working directory"),
    ({"either": 3}, "x.either: expected a string or a mapping, got 3"),
    ({"either": {"rate": 2}}, "x.either.rate: expected a value in [0, 1], got 2"),
    ({"inner": {"rate": -1, "chunk": -1}, "names": ["z"]},
     "x.inner.rate: expected a value in [0, 1], got -1.0; x.inner.chunk: expected a value > 0, got -1; "
     "x.names[0]: expected one of ['a', 'b'], got 'z'"),
])
def test_values_outside_their_check_name_the_key_and_the_allowed_values(mapping, message):
    with pytest.raises(SettingsError) as e:
        from_mapping(Outer, mapping, "x")
    assert message in str(e.value)


def test_allowed_values_pass(tmp_path):
    f = tmp_path / "m.csv"
    f.write_text("0\n")
    s = from_mapping(Outer, {"inner": {"rate": 1, "counts": [1], "chunk": 3}, "names": ["b", "a"], "matrix": str(f),
                             "path": str(f)})
    assert s.inner == Inner(1.0, (1,), 3) and s.matrix == str(f)


def test_yaml_files_are_read_in_one_line_naming_the_file(tmp_path):
    (tmp_path / "ok.yaml").write_text("a: 1\n")
    assert read_yaml(tmp_path / "ok.yaml") == {"a": 1}
    (tmp_path / "latin1.yaml").write_bytes(b"a: \xe9\n")
    for name, message in [("missing.yaml", "cannot read it (No such file or directory)"),
                          ("latin1.yaml", "not UTF-8 text (invalid continuation byte at byte 3)")]:
        with pytest.raises(SettingsError) as e:
            read_yaml(tmp_path / name, "card")
        assert str(e.value) == f"card {tmp_path / name}: {message}"


def test_unknown_top_level_keys():
    check_keys({"seed": 0}, ("seed",))
    with pytest.raises(SettingsError, match=r"^foo, zap: unknown keys; known: \['seed'\]$"):
        check_keys({"seed": 0, "zap": 1, "foo": 2}, ("seed",))
    with pytest.raises(SettingsError, match=r"^sched: unknown keys \['foo'\]"):
        check_keys({"foo": 2}, ("planner",), "sched")


SETTINGS = [evo.DockingSettings, evo.ArmSceneSettings, sched.SchedSettings, surrogate.SurrogateSettings,
            pipeline.PipelineSettings]


def _classes(cls, seen):
    if cls in seen:
        return
    seen.append(cls)
    for f in dataclasses.fields(cls):
        default = f.default if f.default is not dataclasses.MISSING else None
        if dataclasses.is_dataclass(default):
            _classes(type(default), seen)
        elif f.default_factory is not dataclasses.MISSING and dataclasses.is_dataclass(d := f.default_factory()):
            _classes(type(d), seen)


def test_shipped_defaults_are_allowed():
    seen = []
    for cls in SETTINGS:
        _classes(cls, seen)
    checked = 0
    for cls in seen:
        for f in dataclasses.fields(cls):
            check = f.metadata.get("check")
            required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            if check is not None and not required:
                default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
                assert check.problems(default, f"{cls.__name__}.{f.name}") == []
                checked += 1
    assert checked > 40
