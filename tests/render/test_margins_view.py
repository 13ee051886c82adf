"""The sheet's 'Margins as patched': thesis-case2's sheet states its loop as patched beside the
design's, the figures python-control gives for the read-back law; a patch that loses the design's
phase margin says so at the top."""

import json
import re
from html import unescape

import control
import pytest

from patchgen.bench.diagnosis import as_patched_on_bench
from patchgen.design.lti import load_design
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.render.margins_view import percent, pole_text
from patchgen.render.patchfiles import patch_files
from tests.patch.test_as_patched import _plant_ss, _wired_ss, control_margins

M = load_machine("gp6")
BENCH = load_bench("uw-1991")


def _sheet(units):
    d = load_design("thesis-case2")
    d = load_design(d.spec.model_copy(update={"patch": d.spec.patch.model_copy(update={"max_units": units})}))
    net = build_patch(d, M)
    return d, net, patch_files(d, M, net, judged=as_patched_on_bench(d, net, M, BENCH))


@pytest.fixture(scope="module", params=[4, 3])
def sheet(request):
    return (request.param, *_sheet(request.param))


def _row(md: str, loop: str, law: str) -> str:
    """The margins cell of one row of the sheet's 'Margins as patched' table."""
    part = md.split("## Margins as patched", 1)[1]
    return re.search(rf"^\| {re.escape(loop)} \| {re.escape(law)} \| ([^|]*) \|", part, re.M).group(1)


def _figures(cell: str) -> tuple[float, float | None, float]:
    lower = float(re.search(r"lower GM [0-9.]+ \(([-+0-9.]+) dB\)", cell).group(1))
    up = re.search(r"upper GM (?:inf|[0-9.]+ \(([-+0-9.]+) dB\))", cell).group(1)
    return lower, None if up is None else float(up), float(re.search(r"PM ([0-9.]+) deg", cell).group(1))


def test_thesis_case2s_sheet_states_its_margins_as_patched(sheet):
    units, d, net, files = sheet
    md, html = files["patch-sheet.md"], files["patch-sheet.html"]
    lower, upper, pm = control_margins(-control.series(_plant_ss(d), _wired_ss(net)))
    got = _figures(_row(md, "design model", "as patched"))
    assert got[0] == pytest.approx(lower, abs=0.005) and got[2] == pytest.approx(pm, abs=0.005)
    assert (got[1] is None) == (upper is None) and (upper is None or got[1] == pytest.approx(upper, abs=0.005))
    ctl = d.controller
    designed = control_margins(-control.series(_plant_ss(d), control.ss(ctl.Ac, ctl.Bc, ctl.Cc, ctl.Dc)))
    assert _figures(_row(md, "design model", "as designed (kalman)")) == pytest.approx(designed, abs=0.005)
    if units == 4:  # its fast pair kept: the design's loop
        assert got == pytest.approx((-9.31, 18.33, 52.83), abs=0.005)
        assert "kept 100 % of the design's PM" in md and "As patched, the loop" not in md
        bench = _row(md, "uw-1991 bench, linearised (actuator lag 0.2 s)", "as patched")
        assert _figures(bench) == pytest.approx((-7.40, 23.69, 29.12), abs=0.005)
    else:  # residualised: the 14.9 deg against the design's 52.8, and no upper gain margin
        assert got == (pytest.approx(-12.11, abs=0.005), None, pytest.approx(14.86, abs=0.005))
        assert ("> **As patched, the loop on the design model keeps 28 % of the design's phase margin (14.9 of 52.8 "
                "deg): no realisation tried that fits the machine keeps 80 %.") in md
        bench = _row(md, "uw-1991 bench, linearised (actuator lag 0.2 s)", "as patched")
        assert bench == "not stable, rightmost pole +0.1003 ± 10.77j"
        assert "50 % at 30, 76 % at 100 rad/s" in md
    # the HTML sheet says the same
    assert f"<td>{_row(md, 'design model', 'as patched')}</td>" in unescape(html)
    assert "Margins as patched" in html


def test_margins_json_is_among_the_files(sheet):
    units, d, net, files = sheet
    doc = json.loads(files["margins.json"])
    assert doc["loops"][2]["loop"] == "uw-1991 bench, linearised (actuator lag 0.2 s)"
    assert doc["keeps_pm_share"] is (units == 4)


@pytest.mark.parametrize("x, text", [(0.76183, "76 %"), (1.0009, "100 %"), (0.0886, "8.9 %"), (0.0020963, "0.21 %"),
                                     (3e-5, "< 0.01 %")])
def test_percent(x, text):
    assert percent(x) == text


@pytest.mark.parametrize("z, text", [(0.1003 + 10.77j, "+0.1003 ± 10.77j"), (-1e-5 + 0j, "−1e−05"), (3e-18 + 0j, "0"),
                                     (-66.9 - 66.53j, "−66.9 ± 66.53j")])
def test_pole_text(z, text):
    assert pole_text(z) == text
