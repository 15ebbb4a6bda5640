"""Bad scenarios are refused before any stage runs: exit 2 and one line naming the file, the key
and what is allowed (the scenario schema, uvms_jax.plan.check_scenario; docs/scenarios.md)."""

from __future__ import annotations

import copy

import pytest
import yaml
from _battery import ROOT, one_line, run_cases

from uvms_jax.plan import SceneSpec
from uvms_jax.settings import MAX_YAML_BYTES, SettingsError

THESIS = yaml.safe_load((ROOT / "configs" / "scenario" / "thesis_cage.yaml").read_text())


def _scenario(**change) -> dict:
    """The thesis's scene (open water) with ``change`` applied (key → value; a callable edits)."""
    s = copy.deepcopy(THESIS)
    s["cage"] = None
    for key, value in change.items():
        if callable(value):
            value(s)
        else:
            s[key] = value
    return s


def _alias_bomb() -> str:
    """Nine nested anchors, each nine of the one before: 9⁹ values when expanded."""
    lines = ["defaults: [thesis_tables, _self_]", "name: bomb", "x0: &x0 [a, a, a, a, a, a, a, a, a]"]
    lines += [f"x{i}: &x{i} [{', '.join([f'*x{i - 1}'] * 9)}]" for i in range(1, 10)]
    return "\n".join(lines) + "\n"


BIG = "defaults: [thesis_tables, _self_]\n# " + "x" * MAX_YAML_BYTES + "\n"  # a comment longer than any YAML read
# (file name, its text) → a piece of the one line.
FILES = {
    "big": (BIG, f"big.yaml: {len(BIG)} bytes of YAML, more than the {MAX_YAML_BYTES} allowed"),
    "bomb": (_alias_bomb(), "bomb.yaml, line 1: with its aliases expanded, the document holds more than 100000"),
    "dup": ("defaults: [thesis_tables, _self_]\nname: dup\ngravity: 9.81\ngravity: 1.0\n",
            "dup.yaml, line 4: found duplicate key 'gravity'"),
    "yaww": (yaml.safe_dump(_scenario(tables=lambda s: s["tables"][1].update(yaww=0.1))),
             "yaww.yaml: scenario.tables[1]: unknown keys ['yaww']"),
    "objcts": (yaml.safe_dump(_scenario(objcts=[])), "objcts.yaml: scenario: unknown keys ['objcts']"),
    "quote": (yaml.safe_dump(_scenario(tables=lambda s: s["tables"][0].update(name='a"b'))),
              "quote.yaml: scenario: names ['a\"b']: expected letters, digits"),
}
TABLES = "configs/scenario/thesis_tables.yaml: "
# Overrides of the default scenario → a piece of the one line.
OVERRIDES = [
    ("~scenario.objects", TABLES + "scenario.objects: missing (required)"),
    ("~scenario.tables", TABLES + "scenario.tables: missing (required)"),
    ("~scenario.arm.mount_pos", TABLES + "scenario.arm.mount_pos: missing (required)"),
    ("scenario.start_q=[1,a,2,3,4,5]", TABLES + "scenario.start_q[1]: expected a number, got 'a'"),
    ("scenario.tables.1.size=[-0.3,0.3,0.08]", TABLES + "scenario.tables[1].size[0]: expected a value > 0, got -0.3"),
    ("scenario.objects.0.at=[nan,0.0]", TABLES + "scenario.objects[0].at[0]: expected a finite number, got nan"),
    ("scenario.arm.mount_pos=[inf,0,0.9]", TABLES + "scenario.arm.mount_pos[0]: expected a finite number, got inf"),
    ("scenario.gravity=nan", TABLES + "scenario.gravity: expected a finite number, got nan"),
    ("scenario.object_density=-1240", TABLES + "scenario.object_density: expected a value in (0, 25000], got -1240"),
    ("scenario.start_q=[9,0,0,0,0,0]", TABLES + "scenario.start_q[0] (G): 9 is outside [0, 6.3] rad"),
    ("scenario.bases=[]", TABLES + "scenario: bases: expected at least one, got none"),
    ("scenario.objects.0.size=[nan,0.08,0.08]", TABLES + "scenario.objects[0].size[0]: expected a finite number"),
    ("scenario.objects.1.name=cube1", TABLES + "scenario: object and base names must be unique; repeated: ['cube1']"),
    ("scenario.objects.1.table=nowhere", TABLES + "scenario: 'cube2': table 'nowhere' is not one of the tables"),
    ("scenario.bases.0.fits=[cube9]", TABLES + "scenario: base 'base_cube1': fits ['cube9']"),
    ("baseline.water_density=inf", "configs/scenario/thesis_cage.yaml: baseline.water_density: expected a finite"),
]


@pytest.fixture(scope="module")
def refusals(tmp_path_factory):
    """Every case's result, from one child process (the imports once)."""
    tmp = tmp_path_factory.mktemp("scenario")
    (tmp / "configs" / "scenario").mkdir(parents=True)
    for name, (text, _) in FILES.items():
        (tmp / "configs" / "scenario" / f"{name}.yaml").write_text(text)
    cases = [[f"hydra.run.dir={tmp / name}", f"hydra.searchpath=[file://{tmp / 'configs'}]", f"scenario={name}"]
             for name in FILES]
    cases += [[f"hydra.run.dir={tmp / f'o{i}'}", override] for i, (override, _) in enumerate(OVERRIDES)]
    results = run_cases("pipeline.py", cases)
    return dict(zip([*FILES, *(o for o, _ in OVERRIDES)], results)), tmp


@pytest.mark.parametrize("case", [*FILES, *(o for o, _ in OVERRIDES)])
def test_bad_scenario_is_one_line_exit_2(refusals, case):
    results, tmp = refusals
    expected = FILES[case][1] if case in FILES else dict(OVERRIDES)[case]
    line = one_line(results[case])
    assert line.startswith("error: ") and expected in line, line
    name = case if case in FILES else f"o{[o for o, _ in OVERRIDES].index(case)}"
    assert not (tmp / name / "results.json").exists() and not (tmp / name / "RUNNING").exists()


def test_shipped_scenarios_pass_the_schema():
    for path in (ROOT / "configs" / "scenario").glob("*.yaml"):
        scenario = {**THESIS, **yaml.safe_load(path.read_text())}
        scenario.pop("defaults", None)
        assert SceneSpec.from_mapping(scenario).objects, path


def test_every_bad_key_in_one_message():
    bad = _scenario(gravity=float("nan"), water_density=-1.0, tables=lambda s: s["tables"][0].update(pos=[0, 0]))
    with pytest.raises(SettingsError) as e:
        SceneSpec.from_mapping(bad)
    assert str(e.value) == ("scenario.tables[0].pos: expected 3 values, got 2; scenario.water_density: expected a value "
                            "in [0, 1300], got -1.0; scenario.gravity: expected a finite number, got nan")
