"""Bad arm cards and ``uvms-hw --config`` files: read by the one bounded YAML loader
(uvms_jax.settings.read_yaml) and checked against their schemas before anything is built; the
library raises a ValueError naming the file and the key, ``uvms-hw`` and the pipeline exit 2
with that one line."""

from __future__ import annotations

import time

import pytest
from _battery import CASE_LIMIT_S, ROOT, USAGE_EXIT, one_line, run_cases

from uvms_jax.hw import cli
from uvms_jax.robot import load_arm, robot_from_config
from uvms_jax.settings import MAX_YAML_BYTES

BRAVO7 = ROOT / "uvms_jax" / "robot" / "descriptions" / "bravo7.urdf"
PLAN = ROOT / "examples" / "thesis_plan.json"


def _alias_bomb(first: str) -> str:
    """Nine nested anchors, each nine of the one before: 9⁹ values when expanded."""
    lines = [first, "x0: &x0 [a, a, a, a, a, a, a, a, a]"]
    lines += [f"x{i}: &x{i} [{', '.join([f'*x{i - 1}'] * 9)}]" for i in range(1, 10)]
    return "\n".join(lines) + "\n"


GOOD = f"description: {BRAVO7}\ntip: tool\nlink_radius: 0.04\n"
HUGE = "# " + "x" * MAX_YAML_BYTES + "\n" + GOOD  # a good card after a comment longer than any YAML read
# Arm cards: (file name, its text) → a piece of the one line (after "arm card <file>").
CARDS = {
    "bomb": (_alias_bomb(GOOD.splitlines()[0]),
             ", line 1: with its aliases expanded, the document holds more than 100000 values"),
    "dup": (GOOD + "tip: A\n", ", line 4: found duplicate key 'tip'"),
    "nan": (GOOD.replace("0.04", ".nan"), ": link_radius: expected a finite number, got nan"),
    "unknown": (GOOD + "tipp: tool\n", ": tipp: unknown key; known: ['base', 'buoyancy', 'collision'"),
    "type": (GOOD + "finger_size: abc\n", ": finger_size: expected a list, got 'abc'"),
    "range": (GOOD + "gripper_velocity: -0.1\n", ": gripper_velocity: expected a value in (0, 10], got -0.1"),
    "nested": (GOOD + "buoyancy: {link_B: {volume: 1.0e-4, cob: [0, 0, .inf]}}\n",
               ": buoyancy.link_B.cob[2]: expected a finite number, got inf"),
    "ids": (GOOD + "hardware: {protocol: bpl, device_ids: {A: 1, B: 1}}\n",
            ": hardware: device_ids: expected distinct ids, got {'A': 1, 'B': 1}"),
    "list": ("- description\n- tip\n", ": expected a mapping of arm settings, got list"),
    "deep": ("description: " + "[" * 70 + "]" * 70 + "\n", ", line 1: nested deeper than 64 levels"),
    "huge": (HUGE, f": {len(HUGE)} bytes of YAML, more than the {MAX_YAML_BYTES} allowed"),
}
# uvms-hw --config files → a piece of the one line (after "--config <file>").
CONFIGS = {
    "bomb": (_alias_bomb("executor: {}"), ", line 1: with its aliases expanded, the document holds more than"),
    "dup": ("executor: {rate_hz: 50}\nexecutor: {}\n", ", line 2: found duplicate key 'executor'"),
    "nan": ("executor: {rate_hz: .nan}\n", ": hw.executor.rate_hz: expected a finite number, got nan"),
    "unknown": ("executor: {rate: 50}\n", ": hw.executor: unknown keys ['rate']"),
    "type": ("sim: {seed: abc}\n", ": hw.sim.seed: expected an integer, got 'abc'"),
}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cards")
    for kind, files in (("card", CARDS), ("config", CONFIGS)):
        for name, (text, _) in files.items():
            (tmp / f"{kind}_{name}.yaml").write_text(text)
    return tmp


def _hw(capsys, *args: str) -> str:
    """The one line of a refused ``uvms-hw run PLAN --dry-run ARGS``, within the time limit."""
    t = time.perf_counter()
    code = cli.main(["run", str(PLAN), "--dry-run", *args])
    seconds = time.perf_counter() - t
    captured = capsys.readouterr()
    lines = [line for line in (captured.out + captured.err).splitlines() if line.strip()]
    assert code == USAGE_EXIT and len(lines) == 1 and "Traceback" not in captured.err, lines
    assert seconds < CASE_LIMIT_S
    return lines[0]


@pytest.mark.parametrize("name", CARDS)
def test_uvms_hw_refuses_a_bad_arm_card_in_one_line(folder, capsys, name):
    path = folder / f"card_{name}.yaml"
    line = _hw(capsys, "--robot", str(path))
    assert line.startswith(f"uvms-hw: arm card {path}{CARDS[name][1]}"), line


@pytest.mark.parametrize("name", CONFIGS)
def test_uvms_hw_refuses_a_bad_config_in_one_line(folder, capsys, name):
    path = folder / f"config_{name}.yaml"
    line = _hw(capsys, "--config", str(path))
    assert line.startswith(f"uvms-hw: --config {path}{CONFIGS[name][1]}"), line


@pytest.mark.parametrize("name", ["bomb", "dup", "nan", "unknown", "type"])
def test_the_library_names_the_card_and_the_key(folder, name):
    path = folder / f"card_{name}.yaml"
    with pytest.raises(ValueError) as e:
        load_arm(str(path))
    assert str(e.value).startswith(f"arm card {path}{CARDS[name][1]}") and "\n" not in str(e.value)


def test_settings_beside_a_card_are_checked_by_key():
    with pytest.raises(ValueError, match=r"^arm\.link_radius: expected a value in \(0, 0\.5\], got 2\.0; "
                                         r"arm\.gripper\.upper: expected a finite number, got nan$"):
        robot_from_config({"card": "bravo7", "link_radius": 2.0,
                           "gripper": {"joint": "jaws", "lower": 0.0, "upper": float("nan"), "velocity": 0.1}})


def test_shipped_cards_pass_the_schema():
    for name in ("bravo7", "alpha5"):
        assert load_arm(name).gripper is not None


def test_the_pipeline_refuses_a_bad_card_in_one_line(folder):
    names = ["bomb", "dup", "nan", "unknown", "type"]
    cases = [[f"hydra.run.dir={folder / f'run_{n}'}", f"scenario.arm.card={folder / f'card_{n}.yaml'}"] for n in names]
    for name, result in zip(names, run_cases("pipeline.py", cases)):
        line = one_line(result)
        path = folder / f"card_{name}.yaml"
        assert line.startswith(f"error: configs/scenario/thesis_tables.yaml: scenario.arm: arm card {path}"
                               f"{CARDS[name][1]}"), line
        assert not (folder / f"run_{name}" / "RUNNING").exists()
