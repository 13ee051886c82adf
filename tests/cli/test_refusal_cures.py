"""A refusal that one change to the spec would lift names that change: the field and a value the
refusing search found and checked by running the stage with it. Applying it makes `patchgen
patch` succeed; a change not checked is never offered."""

from __future__ import annotations

import pickle
import re

from patchgen.design import corner
from patchgen.inputs.errors import Cure, InputError, ResourceError
from tests.cli_run import run_patchgen
from tests.conftest import design_path

SHIPPED = design_path("bench-recommended").read_text()


def spec_file(tmp_path, name: str, text: str):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def with_lines(text: str, table: str, *lines: str) -> str:
    """The spec's text with ``lines`` added at the top of ``[table]`` (the table added when missing)."""
    if f"\n[{table}]" not in text:
        return text + f"\n[{table}]\n" + "\n".join(lines) + "\n"
    return text.replace(f"\n[{table}]", f"\n[{table}]\n" + "\n".join(lines), 1)


def refusal(path) -> str:
    r = run_patchgen("patch", path, "-o", path.with_suffix(".out"), "--no-predict")
    assert r.returncode == 2 and r.stdout == "", r.stderr
    return r.stderr


def patches(path) -> None:
    r = run_patchgen("patch", path, "-o", path.with_suffix(".out"), "--no-predict")
    assert r.returncode == 0, r.stderr


def heavier_and_looser() -> str:
    """bench-recommended with a 4 kg cart and theta's excursion 0.02 rad: each change alone
    patches, together the roll-off search finds no speed with 30 deg of phase margin."""
    text = re.sub(r"(?m)^M = 3\.552 ", "M = 4.0 ", SHIPPED)
    text = text.replace("theta = 0.01,", "theta = 0.02,")
    assert text.count("M = 4.0") == 1 and "theta = 0.02," in text
    return text


def test_the_roll_off_search_names_the_roll_off_that_works(tmp_path):
    text = heavier_and_looser()
    said = refusal(spec_file(tmp_path, "heavy", text))
    assert "estimator: no estimator speed on the grid gives a stable loop with 30 deg of phase margin" in said
    m = re.search(r"estimator\.rolloff_s = ([0-9.e-]+) gives ([0-9.]+) deg.*\(set it in \[estimator\]\)", said)
    assert m, said
    value, pm = float(m.group(1)), float(m.group(2))
    assert pm >= corner.SUGGEST_PM_DEG and value in [float(f"{v:.3g}") for v in corner.ROLLOFF_GRID_S]
    cured = spec_file(tmp_path, "cured", with_lines(text, "estimator", f"rolloff_s = {value}"))
    patches(cured)
    r = run_patchgen("design", cured, "--json")
    assert r.returncode == 0 and f'"rolloff_s": {value}' in r.stdout.replace("\n", "")


def test_a_suggested_speed_is_offered_only_once_its_design_passes():
    tried = [corner.Scored(0.02, 1.0, 25.0), corner.Scored(0.01, 2.0, 28.5), corner.Scored(0.005, 3.0, 29.0),
             corner.Scored(0.001, 9.0, 29.5)]
    refused = corner.NoRobustSpeed(tried)
    assert [s.value for s in refused.fallbacks()] == [0.01, 0.005, 0.001] and "the most is 29.5 deg" in str(refused)
    asked = []

    def margin_with(v):
        asked.append(v)
        if v == 0.01:
            raise InputError("spec", "estimator", "refused")
        return 27.0 if v == 0.005 else 28.4  # the grid's figure is not taken on trust: the design's is

    cure = corner.way_forward(refused, "estimator.rolloff_s", margin_with)
    assert asked == [0.01, 0.005, 0.001]
    assert cure.field == "estimator.rolloff_s" and cure.value == 0.001 and "gives 28.4 deg" in cure.gives
    assert corner.way_forward(refused, "estimator.rolloff_s", lambda v: 20.0) is None


def test_the_rho_search_names_the_rho_max_that_stops_it_in_time(tmp_path):
    text = design_path("bench-lqg").read_text().replace("W = [[2.0, 0.0]", "W = [[2e6, 0.0]")
    text = re.sub(r"(?m)^rho = 1\.0$", 'rho = "auto"', text)
    assert 'rho = "auto"' in text and "2e6" in text
    said = refusal(spec_file(tmp_path, "noisy", text))
    assert "no solution at rho = 10 " in said  # rho = 1 computed, 10 not
    assert "; estimator.rho_max = 1 stops the search at rho = 1, the last it computes" in said
    assert said.rstrip().endswith("(set it in [estimator])")
    patches(spec_file(tmp_path, "stopped", text.replace('rho = "auto"', 'rho = "auto"\nrho_max = 1')))


def test_a_patch_short_of_pots_names_the_units_that_take_it(tmp_path):
    text = SHIPPED.replace('kind = "filtered_differentiator"', 'kind = "reduced_observer"')
    said = refusal(spec_file(tmp_path, "observer", text))
    assert "13 pots" in said
    assert said.rstrip().endswith("; patch.units = 2 places it on 2 slaved units (set it in [patch])")
    patches(spec_file(tmp_path, "two", with_lines(text, "patch", "units = 2")))
    auto = with_lines(text, "patch", 'units = "auto"', "max_units = 1")
    assert "patch.max_units = 2 lets it take 2 slaved units" in refusal(spec_file(tmp_path, "auto", auto))


def test_a_compensator_that_does_not_fit_names_the_realisation_that_does(tmp_path):
    text = with_lines(SHIPPED.replace('kind = "filtered_differentiator"', 'kind = "reduced_observer"'), "patch",
                      'realization = "compensator"', "units = 2")
    said = refusal(spec_file(tmp_path, "compensator", text))
    assert 'patch.realization = "states" fits it on 2 units (set it in [patch])' in said
    patches(spec_file(tmp_path, "states", text.replace('realization = "compensator"', 'realization = "states"')))


def test_no_change_is_named_when_none_is_found(tmp_path):
    text = SHIPPED.replace('kind = "filtered_differentiator"', 'kind = "kalman"')  # 36 pots: no GP-6 pair takes it
    said = refusal(spec_file(tmp_path, "kalman", text))
    assert "36 pots" in said and "(set it in" not in said


def test_a_cure_travels_with_its_error():
    e = ResourceError("spec.toml", "machine", "too big", Cure("patch.units", 2, "places it on 2 slaved units"))
    back = pickle.loads(pickle.dumps(e))
    assert type(back) is ResourceError and back.cure == e.cure and back.line() == e.line()
    assert e.line() == "spec.toml: machine: too big; patch.units = 2 places it on 2 slaved units (set it in [patch])"
    assert e.message == "too big"  # a study that keeps the message keeps it without the suggestion
