"""A spec written back as TOML reads back as the same spec (recommended.toml)."""

import pytest

from patchgen.inputs.resources import shipped
from patchgen.inputs.spec import load_spec
from patchgen.inputs.spec_file import spec_toml
from tests.conftest import ROOT


@pytest.mark.parametrize("name", shipped("design"))
def test_every_shipped_design_round_trips(name, tmp_path):
    spec = load_spec(name)
    path = tmp_path / "again.toml"
    path.write_text(spec_toml(spec, "written back\n\nby a test"))
    again = load_spec(path)
    assert again.model_dump() == spec.model_dump()
    assert path.read_text().startswith("# written back\n#\n# by a test\n")


def test_a_rotary_spec_without_a_cable_limit_round_trips(tmp_path):
    """alpha_limit left out is infinite (no cable): written back, it is left out again, not "inf"."""
    text = (ROOT / "designs" / "qube-servo-2.toml").read_text()
    src = tmp_path / "rotary.toml"
    src.write_text(text.replace("alpha_limit = 3.141592653589793\n", ""))
    spec = load_spec(src)
    assert spec.plant.alpha_limit == float("inf")
    path = tmp_path / "again.toml"
    path.write_text(spec_toml(spec))
    assert "inf" not in path.read_text() and 'model = "rotary-pendulum"' in path.read_text()
    assert load_spec(path).model_dump() == spec.model_dump()


def test_a_cart_spec_is_written_without_its_default_plant_model(tmp_path):
    written = spec_toml(load_spec("bench-recommended"))
    assert "model = \"cart-pendulum\"" not in written and "[plant]" in written


def test_a_profile_named_by_path_is_written_as_an_absolute_path(tmp_path, monkeypatch):
    bench = tmp_path / "my-bench.toml"
    bench.write_bytes((ROOT / "patchgen" / "profiles" / "benches" / "uw-1991.toml").read_bytes())
    text = (ROOT / "designs" / "thesis-ch5.toml").read_text()
    (tmp_path / "spec.toml").write_text(text.replace('bench = "uw-1991"', 'bench = "my-bench.toml"'))
    monkeypatch.chdir(tmp_path)
    written = spec_toml(load_spec("spec.toml"))
    assert f'bench = "{bench.resolve()}"' in written and 'machine = "gp6"' in written
    elsewhere = tmp_path / "sub"
    elsewhere.mkdir()
    (elsewhere / "again.toml").write_text(written)
    monkeypatch.chdir(elsewhere)
    assert load_spec("again.toml").bench == str(bench.resolve())
