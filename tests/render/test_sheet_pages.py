"""The printed sheets of every shipped design on both machines, as patchgen patch writes them (with
the bench prediction): as many pages as the README says, each within A4 and Letter, and every
wiring diagram laid out (as Chromium prints it) with its smallest label at 6 pt or more."""

import re

import pytest

from tests.cli_run import run_patchgen
from tests.conftest import ROOT
from tests.shipped import patch_files_of

from .test_sheet import MM, _pdf_pages

pytestmark = pytest.mark.heavy(20)  # seconds, roughly: see tests/conftest.py

MACHINE_COLUMNS = {"Comdyna GP-6": "gp6", "THE ANALOG THING": "the-analog-thing"}


def readme_pages() -> dict[tuple[str, str], int]:
    """(design, machine) -> pages, from the README's table of the shipped designs' printed pages."""
    lines = (ROOT / "README.md").read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("| design | Comdyna GP-6 |"))
    machines = [MACHINE_COLUMNS[c.strip()] for c in lines[start].strip("|").split("|")[1:]]
    out = {}
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        name, *counts = (c.strip() for c in line.strip("|").split("|"))
        out.update({(name.strip("`"), m): int(c) for m, c in zip(machines, counts)})
    return out


PAGES = readme_pages()

# every svg.wiring as laid out for print: its width (CSS px, 96 to the inch), its viewBox width
# (pt at its own size) and its smallest font size (viewBox units)
MEASURE = """Array.from(document.querySelectorAll('svg.wiring')).map(s => ({
  width: s.getBoundingClientRect().width, view: s.viewBox.baseVal.width,
  font: Math.min(...Array.from(s.querySelectorAll('text')).map(t => parseFloat(getComputedStyle(t).fontSize)))}))"""


@pytest.fixture(scope="module")
def printed(chromium, tmp_path_factory):
    """(design, machine) -> (every file written, the sheet's PDF's page count and page sizes, its
    diagrams as laid out)."""
    out = {}
    for (name, machine) in PAGES:
        files = patch_files_of(name, machine, predict=True)
        page = tmp_path_factory.mktemp(f"{name}-{machine}") / "patch-sheet.html"
        page.write_text(files["patch-sheet.html"], encoding="utf-8")
        pages, boxes = _pdf_pages(chromium.print_pdf(page))
        out[(name, machine)] = (files, pages, boxes, chromium.evaluate_printed(page, MEASURE))
    return out


def test_the_readme_lists_every_shipped_design_that_fits_on_both_machines():
    from tests.shipped import patched_designs

    listed = {name for name, _ in PAGES}
    assert set(patched_designs()) - listed == {"thesis-case1-noint"}
    assert "needs more pots than\neither machine has" in (ROOT / "README.md").read_text()
    assert patch_files_of("thesis-case1-noint", "gp6") is None and patch_files_of("thesis-case1-noint",
                                                                                 "the-analog-thing") is None


@pytest.mark.parametrize("case", list(PAGES), ids=[f"{n}-{m}" for n, m in PAGES])
def test_prints_on_the_pages_the_readme_says(printed, case):
    files, pages, boxes, _ = printed[case]
    html = files["patch-sheet.html"]
    assert pages == PAGES[case], (case, pages)
    assert "Predicted on the bench" in html and "Static check" in html
    for w, h in boxes:   # within A4 (210 x 297 mm) and Letter (215.9 x 279.4 mm)
        assert w <= 210 * MM + 0.5 and h <= 279.4 * MM + 0.5


@pytest.mark.parametrize("case", list(PAGES), ids=[f"{n}-{m}" for n, m in PAGES])
def test_every_diagram_prints_its_smallest_label_at_6_pt_or_more(printed, case):
    """Measured on the page as Chromium lays it out for print: the diagram's printed width against
    its own, times its smallest font (before, bench-lqg's units printed at 4.3 and 5.2 pt)."""
    files, _, _, diagrams = printed[case]
    html = files["patch-sheet.html"]
    assert len(diagrams) == html.count("<figure") >= 1
    for d in diagrams:
        printed_pt = d["font"] * (d["width"] * 72 / 96) / d["view"]
        assert printed_pt >= 6.0 - 1e-6, (case, printed_pt)
        assert d["width"] * 25.4 / 96 <= 186.0 + 0.1
    assert "smallest labels print at" not in html
    if len(diagrams) > 1:  # a unit's diagram, or a part of one, on a page of its own
        assert html.count('<figure class="own-page">') == len(diagrams)


def test_a_three_page_layout_keeps_the_static_check_with_the_sign_check(printed):
    """The static check follows the sign check at once; neither has a page to itself."""
    html = printed[("bench-recommended", "gp6")][0]["patch-sheet.html"]
    order = [html.index(h) for h in ("<h2>Wiring diagram", "<h2>Procedure", "<h2>Sign check", "<h2>Static check",
                                     "<h2>Margins as patched", "<h2>Predicted on the bench")]
    assert order == sorted(order)


def test_the_sheets_text_is_7_pt_or_more():
    """Tables, notes and captions at 7 pt or more (they were 6.2 to 6.6 pt)."""
    from patchgen.inputs.resources import folder

    css = folder("template").joinpath("patch-sheet.html.j2").read_text().split("</style>")[0]
    sizes = [float(x) for x in re.findall(r"font(?:-size)?:\s*([0-9.]+)pt", css)]
    assert sizes and min(sizes) >= 7.0


def test_a_swingup_sheet_prints_as_the_patch_sheet_does(chromium, tmp_path):
    out = tmp_path / "out"
    r = run_patchgen("swingup", "bench-recommended", "-o", str(out))
    assert r.returncode == 0, r.stderr
    pages, _ = _pdf_pages(chromium.print_pdf(out / "patch-sheet.html"))
    assert pages == PAGES[("bench-recommended", "gp6")]
    assert "<h2>Pump-up schedule" in (out / "patch-sheet.html").read_text()


def test_a_machine_named_with_its_own_article_gets_no_other(printed):
    """THE ANALOG THING is never 'the THE ANALOG THING' (the pot table's title and the static
    check's caption once said so), in any file of any sheet."""
    for (name, machine), (files, *_) in printed.items():
        for file, text in files.items():
            assert "the THE" not in text and "The THE" not in text, (name, machine, file)
    assert any("THE ANALOG THING" in files["patch-sheet.md"] for files, *_ in printed.values())
