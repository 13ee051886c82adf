"""Turning TOML and pydantic's complaints into one line naming the file and the field."""

from __future__ import annotations

import math

import pytest
from pydantic import Field

from patchgen.inputs.errors import InputError
from patchgen.inputs.fields import InputModel, Real, bounded
from patchgen.inputs.validation import field_path, parse_toml, validate


class Inner(InputModel):
    tau: Real = bounded(0, 10)


class Outer(InputModel):
    name: str = Field(min_length=1)
    gains: list[Real] = Field(default_factory=list)
    inner: Inner


def _error(data) -> InputError:
    with pytest.raises(InputError) as exc:
        validate(Outer, data, "spec.toml")
    return exc.value


def test_field_paths_read_as_written():
    assert field_path(("inner", "tau")) == "inner.tau"
    assert field_path(("gains", 2)) == "gains[2]"
    assert field_path(("amplifiers", 0, "inputs", "x1")) == "amplifiers[0].inputs.x1"
    assert field_path(()) == ""


def test_a_good_document_validates():
    m = validate(Outer, {"name": "a", "gains": [1, 2.5], "inner": {"tau": 0.2}}, "spec.toml")
    assert m.inner.tau == 0.2 and m.gains == [1.0, 2.5]


@pytest.mark.parametrize("data, field", [
    ({"name": "a", "inner": {"tau": 11.0}}, "inner.tau"),              # out of range
    ({"name": "a", "inner": {"tau": "fast"}}, "inner.tau"),            # wrong type
    ({"name": "a", "inner": {"tau": math.nan}}, "inner.tau"),          # not finite
    ({"name": "a", "inner": {"tau": math.inf}}, "inner.tau"),
    ({"name": "a", "inner": {"tau": True}}, "inner.tau"),              # a bool is no number
    ({"name": "a", "gains": [1.0, "x"], "inner": {"tau": 1}}, "gains[1]"),
    ({"name": "a", "inner": {}}, "inner.tau"),                         # missing
    ({"name": "a", "inner": {"tau": 1, "taux": 2}}, "inner.taux"),     # unknown key
    ({"name": "", "inner": {"tau": 1}}, "name"),
])
def test_each_problem_is_one_line_naming_the_field(data, field):
    e = _error(data)
    assert e.source == "spec.toml" and e.field == field
    assert e.exit_status == 2 and "\n" not in str(e)


def test_the_wrong_value_is_shown_as_toml_would_write_it():
    assert "(got 11.0)" in _error({"name": "a", "inner": {"tau": 11.0}}).message
    assert "(got true)" in _error({"name": "a", "inner": {"tau": True}}).message


def test_toml_syntax_errors_name_the_file_and_line():
    with pytest.raises(InputError) as exc:
        parse_toml(b"name = 'a'\ntau = = 3\n", "bad.toml")
    assert exc.value.source == "bad.toml" and "line 2" in exc.value.message
    with pytest.raises(InputError) as exc:
        parse_toml(b"\xff\xfe not utf-8", "bin.toml")
    assert exc.value.source == "bin.toml"
