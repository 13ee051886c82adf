"""`patchgen check SPEC --readings FILE`: the static-check CSV a patch writes, filled in with
readings of a right and of a wrongly patched machine, and with bad values."""

import csv
import io
import json
from dataclasses import replace

import numpy as np
import pytest
from click.testing import CliRunner

from patchgen.cli import cli
from patchgen.patch.fault_finding import diagnose_readings, predict
from patchgen.patch.readings import reading_limit_V
from patchgen.patch.static_check import static_check, wires_of
from patchgen.pipeline.scaling import scaled_patch
from patchgen.profiles.bench import load_bench
from tests.conftest import design_from_path, design_path


@pytest.fixture(scope="module")
def patched(tmp_path_factory):
    out = tmp_path_factory.mktemp("patch")
    r = CliRunner().invoke(cli, ["patch", "bench-recommended", "-o", str(out), "--no-predict"])
    assert r.exit_code == 0, r.output
    d, m = design_from_path(design_path("bench-recommended"))
    net = scaled_patch(d, m, load_bench(d.spec.bench)).netlist  # the patch every command builds
    return out / "static-check.csv", net, m, static_check(net, m)


def _filled(path, values, tmp_path, name="filled.csv"):
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    for r, v in zip(rows, values):
        r["measured_V"] = f"{v:.4f}"
    target = tmp_path / name
    with target.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return target


def _check(path, *extra):
    return CliRunner().invoke(cli, ["check", "bench-recommended", "--readings", str(path), *extra])


def test_the_written_csv_is_the_checks(patched):
    path, net, m, check = patched
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    assert [(r["condition"], r["point"]) for r in rows] == [(x.condition, x.point) for x in check.readings]
    assert [float(r["expected_V"]) for r in rows] == pytest.approx([x.expected_V for x in check.readings], abs=5e-5)


def test_correct_readings_agree(patched, tmp_path):
    path, net, m, check = patched
    tol = np.array([r.tolerance_V for r in check.readings])
    good = predict(net, check, wires_of(net)) + 0.5 * tol * np.sin(np.arange(len(tol)))
    r = _check(_filled(path, good, tmp_path))
    assert r.exit_code == 0, r.output
    assert f"all {len(check.readings)} readings agree" in r.output


@pytest.mark.parametrize("fault, expect", [
    ("P4 at 0.815", "P4 set to about 0.815 instead of 0.915"),
    ("P3 fed from theta", "A7 x1a: P3 fed from theta instead of s"),
    ("P6 reversed", "A8 x1a (P6): sign reversed"),
])
def test_a_wrong_patch_names_its_fault_first(patched, tmp_path, fault, expect):
    path, net, m, check = patched
    wires = wires_of(net)
    k = next(i for i, w in enumerate(wires) if w.pot == fault.split()[0])
    w = wires[k]
    bad = {"P4 at 0.815": replace(w, gain=w.weight * 0.815), "P3 fed from theta": replace(w, source="theta"),
           "P6 reversed": replace(w, gain=-w.gain)}[fault]
    readings = predict(net, check, wires[:k] + [bad] + wires[k + 1:], m.imperfections.saturation_V)
    r = _check(_filled(path, readings, tmp_path), "--json")
    assert r.exit_code == 1, r.output
    rep = json.loads(r.stdout)
    assert not rep["agree"] and rep["mismatched"]
    assert rep["faults"][0]["description"].startswith(expect), rep["faults"][:3]
    text = _check(_filled(path, readings, tmp_path, "again.csv"))
    assert text.exit_code == 1 and expect in text.output
    # what the terminal says is in the JSON: the count of readings disagreeing, and whether more
    # than one fault explains them all
    assert f"{len(rep['mismatched'])} of {rep['readings']} readings disagree" in text.output
    assert rep["readings"] == len(check.readings)
    assert rep["ambiguous"] == ("more than one fault explains" in " ".join(text.output.split()))


def _last_field(text, value):
    lines = text.splitlines()
    lines[1] = lines[1].rsplit(",", 1)[0] + "," + value
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("edit, field", [
    (lambda t: t.replace("measured_V", "reading"), "header"),
    (lambda t: _last_field(t, "abc"), "row 2: measured_V"),
    (lambda t: _last_field(t, "nan"), "row 2: measured_V"),
    (lambda t: t.replace("IC,A1", "IC,A9", 1), "row 2"),
    (lambda t: "\n".join(t.splitlines()[:-1]) + "\n", "measured_V"),
])
def test_a_bad_readings_file_is_one_line_and_exit_2(patched, tmp_path, edit, field):
    path, net, m, check = patched
    filled = _filled(path, [r.expected_V for r in check.readings], tmp_path).read_text()
    bad = tmp_path / "bad.csv"
    bad.write_text(edit(filled))
    r = CliRunner().invoke(cli, ["check", "bench-recommended", "--readings", str(bad)])
    assert r.exit_code == 2, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and str(bad) in lines[0] and field in lines[0], r.output
    assert "Traceback" not in r.output


def test_a_missing_readings_file_is_one_line(tmp_path):
    r = CliRunner().invoke(cli, ["check", "bench-recommended", "--readings", str(tmp_path / "none.csv")])
    assert r.exit_code == 2 and len(r.output.strip().splitlines()) == 1


@pytest.mark.parametrize("edit", [
    pytest.param(lambda t: "\ufeff" + t, id="utf8-bom"),
    pytest.param(lambda t: t.replace("\n", "\r\n"), id="crlf"),
    pytest.param(lambda t: t.replace("\n", "\n\n", 3), id="blank-lines"),
    pytest.param(lambda t: t + t.splitlines()[1] + "\n", id="row-twice-same-value"),
    pytest.param(lambda t: "\n".join(ln + (",notes" if i == 0 else ",") for i, ln in enumerate(t.splitlines())),
                 id="extra-column"),
    pytest.param(lambda t: t.replace(",", " , ", 6), id="spaces-around-cells"),
])
def test_a_readings_file_as_a_spreadsheet_saves_it_is_read(patched, tmp_path, edit):
    """What a spreadsheet writes (a byte-order mark, CRLF, blank lines, a notes column) is valid."""
    path, net, m, check = patched
    filled = _filled(path, [r.expected_V for r in check.readings], tmp_path).read_text()
    target = tmp_path / "saved.csv"
    target.write_bytes(edit(filled).encode("utf-8"))
    r = CliRunner().invoke(cli, ["check", "bench-recommended", "--readings", str(target)])
    assert r.exit_code == 0, r.output
    assert f"all {len(check.readings)} readings agree" in r.output


def test_readings_at_the_limit_give_finite_chi_squares(patched, tmp_path):
    """The largest readings accepted (ten times the reference) keep every chi-square finite."""
    path, net, m, check = patched
    limit = reading_limit_V(m)
    values = [limit * (-1) ** k for k in range(len(check.readings))]
    r = _check(_filled(path, values, tmp_path), "--json")
    assert r.exit_code == 1, r.output
    faults = json.loads(r.stdout)["faults"]
    assert faults and all(np.isfinite(f["chi_square"]) for f in faults)
    over = _check(_filled(path, [v * 1.001 for v in values], tmp_path, "over.csv"))
    assert over.exit_code == 2 and "row 2: measured_V" in over.output


def test_diagnosis_refuses_readings_out_of_range(patched):
    path, net, m, check = patched
    with pytest.raises(ValueError, match="finite"):
        diagnose_readings(net, m, check, np.full(len(check.readings), 1e200))
