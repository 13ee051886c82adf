"""The documented netlist schema is the one the code writes."""

import json

import pytest

from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.patch.netlist import SCHEMA_ID, Netlist, json_schema
from tests.conftest import ROOT, design_from_path, design_path
from tests.golden import assert_matches, outputs_and_spreads


def test_schema_file_is_current():
    assert json.loads((ROOT / "docs" / "netlist.schema.json").read_text()) == json_schema()


def test_written_netlist_is_deterministic_and_reads_back():
    d, m = design_from_path(design_path("thesis-ch5"))
    a, b = build_patch(d, m).to_json(), build_patch(*design_from_path(design_path("thesis-ch5"))).to_json()
    assert a == b
    data = json.loads(a)
    assert data["schema"] == SCHEMA_ID
    assert Netlist.model_validate_json(a).to_json() == a


# the floor of the golden comparison: far below anything a pot can show; each number's own
# spread under rounding-level moves of the inputs widens it where the design fixes fewer digits
GOLDEN_RTOL, GOLDEN_ATOL = 1e-9, 1e-12


def test_golden_ch5_netlist():
    # the fixture other tests read is what patchgen writes for the section 5.3 design: the same
    # amplifiers, jacks, pots and signs exactly, every number within what it carries
    files, spreads = outputs_and_spreads(load_spec("thesis-ch5"))
    want = json.loads((ROOT / "tests" / "fixtures" / "thesis-ch5.netlist.json").read_text())
    assert_matches(json.loads(files["netlist.json"]), want, GOLDEN_RTOL, GOLDEN_ATOL, "thesis-ch5",
                   spreads["netlist.json"])


def test_golden_comparison_catches_a_changed_sign_or_pot():
    want = json.loads((ROOT / "tests" / "fixtures" / "thesis-ch5.netlist.json").read_text())
    pot = want["pots"][0]
    key = next(k for k, v in pot.items() if isinstance(v, float) and v != 0)
    for changed in ({**pot, key: pot[key] * (1 + 1e-4)}, {**pot, key: -pot[key]}):
        with pytest.raises(AssertionError):
            assert_matches({**want, "pots": [changed, *want["pots"][1:]]}, want, GOLDEN_RTOL, GOLDEN_ATOL)
