"""Cases: from TOML and dicts, --set semantics, named errors."""

from __future__ import annotations

import pytest

import bisph
from conftest import CASES, DAM_BREAK, small_case


def test_round_trip_through_toml_set_dict_and_build():
    case = bisph.Case.from_toml(CASES / "hydrostatic-2d.toml")
    assert (case.name, case.dim) == ("hydrostatic-2d", 2)
    case.set("resolution.dx", 0.05)
    case.set("time.end", 0.05)
    d = case.to_dict()
    assert d["resolution"]["dx"] == 0.05
    again = bisph.Case.from_dict(d)
    assert again.text == case.text
    sim = again.build()
    assert sim.case.text == case.text
    assert sim.n_particles == 200  # 1 m x 0.5 m of water at dx = 0.05
    assert sim.time == 0.0 and sim.steps == 0


def test_set_reads_strings_as_the_command_line_does():
    a, b = small_case(), small_case()
    a.set("resolution.dx", "0.025")
    b.set("resolution.dx", 0.025)
    assert a.text == b.text
    a.set("boundary", "bi")  # not TOML: a string
    assert a.to_dict()["boundary"] == "bi"
    a.set("fluid_block.0.max", [0.5, 0.25])
    assert a.to_dict()["fluid_block"][0]["max"] == [0.5, 0.25]


def test_a_bad_key_raises_the_named_error_with_its_attributes():
    case = small_case()
    before = case.text
    with pytest.raises(bisph.CaseError) as raised:
        case.set("resolution.dxx", 0.01)
    e = raised.value
    assert isinstance(e, ValueError)
    assert e.file == str(CASES / DAM_BREAK[0])
    assert e.key == "resolution.dxx"
    assert "unknown field `dxx`" in e.message and "expected one of" in e.message
    assert e.file in str(e) and e.key in str(e)
    assert case.text == before  # a failed set leaves the case unchanged


def test_a_bad_value_names_its_key():
    with pytest.raises(bisph.CaseError) as raised:
        small_case().set("resolution.dx", "small")
    assert raised.value.key == "resolution.dx"
    with pytest.raises(bisph.CaseError) as raised:
        small_case().set("resolution.dx", -1.0)
    assert raised.value.key == "resolution.dx"


def test_from_dict_names_its_source_and_the_missing_key():
    d = small_case().to_dict()
    del d["fluid"]["density"]
    with pytest.raises(bisph.CaseError) as raised:
        bisph.Case.from_dict(d, source="study.py")
    assert raised.value.file == "study.py"
    assert "density" in raised.value.message


def test_from_dict_refuses_values_toml_cannot_hold():
    d = small_case().to_dict()
    d["resolution"]["dx"] = object()
    with pytest.raises(TypeError, match="resolution.dx"):
        bisph.Case.from_dict(d)


def test_the_default_case_is_the_command_lines():
    case = bisph.Case.default()
    assert case.name == "dam-break-2d"
    assert case.text == bisph.Case.from_toml(CASES / "dam-break-2d.toml").text
