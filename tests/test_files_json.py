"""uvms_jax.files.json_text: the layout of every JSON result file. The oracle is the json module:
``json.loads`` of the text must give back what ``json.dumps`` writes, key order and number types
included; the layout rules are checked line by line."""

from __future__ import annotations

import json
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from uvms_jax.files import LONG_LINE, SHORT_LINE, json_text, write_json

SCALARS = st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=20)
VALUES = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=30) | st.dictionaries(st.text(max_size=10), inner,
                                                                                               max_size=8),
                      max_leaves=200)


@given(VALUES)
def test_the_text_reads_back_as_json_dumps_writes_it(value):
    text = json_text(value)
    assert json.dumps(json.loads(text)) == json.dumps(value)
    assert json.dumps(json.loads(json_text(value, ensure_ascii=False))) == json.dumps(value)


def test_keys_that_are_not_strings_become_json_s_own_strings():
    value = {1: "a", 2.5: "b", True: "c", None: "d", "e": {3: [0] * 60}}
    assert json.loads(json_text(value)) == json.loads(json.dumps(value))


def test_default_and_ensure_ascii_are_json_s():
    value = {"path": Path("/tmp/x"), "angle": "±15°", "rows": [[Path("a"), 1]] * 20}
    text = json_text(value, default=str, ensure_ascii=False)
    assert json.loads(text) == json.loads(json.dumps(value, default=str))
    assert "±15°" in text and "\\u00b1" in json_text(value, default=str)


def test_numbers_and_records_stay_on_one_line():
    series = [i / 7 for i in range(40)]  # about 800 characters: one line, under LONG_LINE
    record = {f"field_{i}": i * 0.1 for i in range(30)}  # a record over SHORT_LINE, still one line
    lines = json_text({"series": series, "record": record, "small": {"a": [1, 2], "b": {"c": None}}}).splitlines()
    assert lines[1] == ' "series": ' + json.dumps(series) + ","
    assert lines[2] == ' "record": ' + json.dumps(record) + ","
    assert lines[3] == ' "small": {"a": [1, 2], "b": {"c": null}}'
    assert len(lines) == 5


def test_a_long_list_fills_lines_up_to_the_long_width():
    series = [i / 7 for i in range(400)]
    lines = json_text({"series": series}).splitlines()
    body = lines[2:-2]
    assert all(len(line) <= LONG_LINE for line in body) and len(body) > 1
    assert all(len(a) + 2 + len(b.split(",")[0].strip()) > LONG_LINE for a, b in zip(body, body[1:]))  # full lines
    assert json.loads("[" + "".join(body) + "]") == series


def test_rows_of_a_matrix_take_a_line_each():
    matrix = [[i + j / 3 for j in range(6)] for i in range(5)]  # over SHORT_LINE on one line
    assert len(json.dumps(matrix)) > SHORT_LINE
    lines = json_text({"q": matrix}).splitlines()
    assert lines[2:-2] == ["  " + json.dumps(row) + "," for row in matrix[:-1]] + ["  " + json.dumps(matrix[-1])]


def test_write_json_ends_with_a_newline(tmp_path):
    path = write_json(tmp_path / "sub" / "r.json", {"a": [1.5, 2]})
    assert path.read_text() == '{"a": [1.5, 2]}\n'
