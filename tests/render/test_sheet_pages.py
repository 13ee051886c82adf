"""The sheets patchgen writes (with their bench prediction) print on at most two pages."""

import json
import re

import pytest

from tests.cli_run import run_patchgen
from tests.conftest import ROOT

from .test_sheet import MM, _pdf_pages, allowed_pages

pytestmark = pytest.mark.heavy(10)  # seconds, roughly: see tests/conftest.py


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """``patchgen *args -o DIR`` run once a module for each ``args``: (the run, DIR). Tests that
    print or read the same sheet share it; none of them writes to DIR."""
    runs = {}

    def write(*args):
        if args not in runs:
            out = tmp_path_factory.mktemp("out")
            runs[args] = (run_patchgen(*args, "-o", str(out)), out)
        return runs[args]

    return write


@pytest.mark.parametrize("args", [
    ["patch", "thesis-ch5", "--runs", "4"],
    ["patch", "bench-recommended", "--runs", "4"],
    ["swingup", "bench-recommended"],
])
def test_written_sheet_fits_two_pages(written, chromium, args):
    r, out = written(*args)
    assert r.returncode == 0, r.stderr
    pages, boxes = _pdf_pages(chromium.print_pdf(out / "patch-sheet.html"))
    assert 1 <= pages <= allowed_pages((out / "patch-sheet.html").read_text())
    assert all(w <= 210 * MM + 0.5 and h <= 279.4 * MM + 0.5 for w, h in boxes)
    assert "Predicted on the bench" in (out / "patch-sheet.html").read_text()


def _variant(tmp_path, name, **changes):
    """A shipped design with some lines changed, written as a spec file."""
    text = (ROOT / "designs" / f"{name}.toml").read_text()
    for old, new in changes.items():
        text = text.replace(old.replace("__", " "), new)
    path = tmp_path / f"{name}-variant.toml"
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize("name", ["thesis-ch5", "bench-recommended"])
def test_the_analog_things_sheet_fits_two_pages_and_a_two_unit_sheet_three(tmp_path, chromium, name):
    that = _variant(tmp_path, name, **{'machine__=__"gp6"': 'machine = "the-analog-thing"'})
    two = tmp_path / "two.toml"
    text = (ROOT / "designs" / f"{name}.toml").read_text()
    text = re.sub(r'kind = "\w*differentiator"', 'kind = "reduced_observer"', text)
    text = re.sub(r"rolloff_s = [^\n]*\n", "", text)
    text = text.replace("[patch]\n", '[patch]\nunits = "auto"\n') if "[patch]" in text else (
        text + '\n[patch]\nunits = "auto"\n')
    two.write_text(text)
    for spec, most in ((that, 2), (str(two), 3)):
        out = tmp_path / f"out-{most}"
        r = run_patchgen("patch", spec, "--runs", "4", "-o", str(out))
        assert r.returncode == 0, r.stderr
        pages, _ = _pdf_pages(chromium.print_pdf(out / "patch-sheet.html"))
        assert 1 <= pages <= allowed_pages((out / "patch-sheet.html").read_text(), most), (spec, pages)
        html = (out / "patch-sheet.html").read_text()
        assert "Static check" in html and (out / "static-check.csv").stat().st_size > 0
        if most == 3:  # a diagram per unit that holds amplifiers (thesis-ch5's second unit lends only pots)
            units = {a["id"].split(".")[0] for a in json.loads((out / "netlist.json").read_text())["amplifiers"]}
            assert all(f"Unit {u} of 2" in html for u in units) and units


@pytest.mark.parametrize("args", [
    ["patch", "thesis-ch5", "--runs", "4"],
    ["patch", "bench-recommended", "--runs", "4"],
    ["patch", "thesis-case1", "--runs", "4"],
    ["patch", "bench-lqg", "--runs", "4"],
])
def test_every_diagram_on_the_sheet_prints_its_smallest_text_at_6pt_or_says_what_it_prints_at(written, args):
    """The sheet shrinks a diagram to the page's 186 mm and to the height it leaves the diagram
    (96, 68 or 46 mm). Each inlined diagram, at the smaller of both scales, prints its smallest
    label at 6 pt or more; one too tall for that on one page fills a page and its caption names the
    size its labels print at (before, the room alone capped them: bench-recommended's labels printed
    at 3.3 pt, bench-lqg's first unit's at 1.2 pt, and nothing said so)."""
    from .svg_geometry import parse, printed_min_font

    r, out = written(*args)
    assert r.returncode == 0, r.stderr
    html = (out / "patch-sheet.html").read_text()
    figures = re.findall(r"<figure>.*?</figure>", html, flags=re.S)
    assert figures
    for fig in figures:
        svg = re.search(r"<svg class=\"wiring\".*?</svg>", fig, flags=re.S).group(0)
        cap = re.search(r'data-room-mm="[0-9.]+" style="max-height: ([0-9.]+)mm"', svg.split(">", 1)[0])
        assert cap, "an inlined diagram without its height cap would fill the page"
        cap_mm = float(cap.group(1))
        printed = printed_min_font(parse(svg), cap_mm / 25.4 * 72)
        said = re.search(r"its smallest labels print at ([0-9.]+) pt", fig)
        if printed >= 6.0 - 1e-9:
            assert said is None, (args[1], printed)
        else:
            assert cap_mm >= 230.0, (args[1], cap_mm, printed)  # a page of the 250 mm, less heading and caption
            assert said is not None and float(said.group(1)) == pytest.approx(printed, abs=0.05), (args[1], printed)
