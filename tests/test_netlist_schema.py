"""The documented netlist schema is the one the code writes."""

import json

from patchgen.cli.design import design_from_path
from patchgen.netlist import SCHEMA_ID, Netlist, json_schema
from patchgen.patch import build_patch

from .conftest import ROOT, design_path


def test_schema_file_is_current():
    assert json.loads((ROOT / "docs" / "netlist.schema.json").read_text()) == json_schema()


def test_written_netlist_is_deterministic_and_reads_back():
    d, m = design_from_path(design_path("thesis-ch5"))
    a, b = build_patch(d, m).to_json(), build_patch(*design_from_path(design_path("thesis-ch5"))).to_json()
    assert a == b
    data = json.loads(a)
    assert data["schema"] == SCHEMA_ID
    assert Netlist.model_validate_json(a).to_json() == a


def test_golden_ch5_netlist():
    # the fixture other tests read is exactly what patchgen writes for the section 5.3 design
    d, m = design_from_path(design_path("thesis-ch5"))
    assert build_patch(d, m).to_json() == (ROOT / "tests" / "fixtures" / "thesis-ch5.netlist.json").read_text()
