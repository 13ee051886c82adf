"""Shipped data inside the package: found by name from any directory, copied out by `examples`."""

from __future__ import annotations

import subprocess
import sys
import tomllib

import pytest

from patchgen.inputs.errors import InputError
from patchgen.inputs.resources import resolve, shipped
from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.spec import load_spec
from tests.conftest import ROOT

SETUPTOOLS = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
DATA_PACKAGES = {"patchgen.designs": "designs", "patchgen.sims": "sims", "patchgen.templates": "templates"}


def test_every_shipped_file_is_package_data():
    # each shipped kind is listed, and pyproject ships its folder's files in the wheel
    kinds = {k: shipped(k) for k in ("design", "scenario", "machine", "bench")}
    assert "bench-recommended" in kinds["design"] and "hold-120s" in kinds["scenario"]
    assert kinds["machine"] == ["gp6", "lucidac", "the-analog-thing"]
    assert kinds["bench"] == ["quanser-ip02", "qube-servo-2", "uw-1991", "uw-1991-uncertain"]
    data = SETUPTOOLS["package-data"]
    for folder in ("profiles/machines", "profiles/benches"):
        assert f"{folder}/*.toml" in data["patchgen"]
    assert data["patchgen.designs"] == data["patchgen.sims"] == ["*.toml"] and data["patchgen.templates"] == ["*.j2"]


def test_the_shipped_data_lives_at_the_top_level_only():
    # designs/, sims/ and templates/ are mapped into the package, and no second copy sits inside it
    assert SETUPTOOLS["package-dir"] == DATA_PACKAGES
    for folder in DATA_PACKAGES.values():
        assert any((ROOT / folder).glob("*.toml")) or any((ROOT / folder).glob("*.j2"))
        assert not (ROOT / "patchgen" / folder).exists()
    for kind, folder in (("design", "designs"), ("scenario", "sims")):
        assert shipped(kind) == sorted(p.stem for p in (ROOT / folder).glob("*.toml"))


def test_every_code_package_is_listed_for_the_wheel():
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "patchgen").rglob("__init__.py")}
    assert set(SETUPTOOLS["packages"]) == found | set(DATA_PACKAGES)


def test_names_load_the_same_as_paths():
    by_path = load_spec(ROOT / "designs" / "thesis-ch5.toml")
    assert load_spec("thesis-ch5").model_dump() == by_path.model_dump()
    by_name = load_scenario("hold-120s")
    assert by_name.model_dump() == load_scenario(ROOT / "sims" / "hold-120s.toml").model_dump()
    assert by_name.name == "hold-120s"


def test_a_file_that_exists_wins_over_a_shipped_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "thesis-ch5").write_text("not a shipped design")
    assert resolve("design", "thesis-ch5") == tmp_path.joinpath("thesis-ch5").relative_to(tmp_path)


def test_unknown_name_lists_the_shipped_ones():
    with pytest.raises(InputError) as e:
        load_spec("bench-recomended")
    assert "no shipped design" in str(e.value) and "bench-recommended" in str(e.value)


def test_examples_copies_every_design_and_scenario_byte_for_byte(tmp_path):
    out = tmp_path / "ex"
    r = subprocess.run([sys.executable, "-m", "patchgen", "examples", str(out)], capture_output=True, text=True,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    for kind, folder in (("design", "designs"), ("scenario", "sims")):
        names = sorted(p.stem for p in (out / folder).glob("*.toml"))
        assert names == shipped(kind)
        for n in names:
            assert (out / folder / f"{n}.toml").read_bytes() == (ROOT / folder / f"{n}.toml").read_bytes()
    # the copies run by path, and a second copy into the same folder is refused
    assert load_spec(out / "designs" / "bench-recommended.toml").name == load_spec("bench-recommended").name
    again = subprocess.run([sys.executable, "-m", "patchgen", "examples", str(out)], capture_output=True, text=True)
    assert again.returncode == 2 and "--force" in again.stderr and len(again.stderr.strip().splitlines()) == 1
