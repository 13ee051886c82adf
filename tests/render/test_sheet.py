"""The patch sheet: tables from the netlist, the sign check, same bytes, and three printed pages."""

import re
from dataclasses import replace
from pathlib import Path

from patchgen.patch.netlist import read_netlist, wire_list
from patchgen.patch.sign_check import sign_check
from patchgen.profiles.machine import Step, load_machine
from patchgen.render.diagram import wiring_svg
from patchgen.render.sheet import SheetSection, SheetSummary, render_sheet

FIXTURE = Path(__file__).parents[1] / "fixtures" / "thesis-ch5.netlist.json"
MM = 72 / 25.4

# The section 5.3 design (designs/thesis-ch5.toml): K for [s, theta, s_dot, theta_dot, int_theta],
# its closed-loop poles and LQR margins as `patchgen design` gives them.
SUMMARY = SheetSummary(
    design="thesis-ch5",
    description="LQR of section 5.3 <as wired>",
    states=["s", "theta", "s_dot", "theta_dot", "int_theta"],
    K=[-15.8114, -156.7625, -22.5763, -35.1574, -3.2248e-05],
    poles=[-12.2835, -2.6682, complex(-1.2542, 1.2377), complex(-1.2542, -1.2377), -0.00001],
    margins={"plant input": {"lower GM": "0.3815 (−8.37 dB)", "PM (deg)": 71.53}},
    estimator="none: theta_dot from a differentiator",
    sections=[SheetSection("Predicted on the bench", ["Quantity", "Value"],
                           [["closed-loop pole with the 0.2 s actuator lag", "+0.32"]])],
)


def _summary(net):
    """SUMMARY with the fixture's sign check on the GP-6."""
    return replace(SUMMARY, signs=sign_check(net, load_machine("gp6")))


def _render():
    net = read_netlist(FIXTURE)
    return net, *render_sheet(net, _summary(net), wiring_svg(net), load_machine("gp6").procedure)


def test_html_pot_table_has_a_row_per_pot():
    net, html, _ = _render()
    rows = re.findall(r"<tr><td><b>(P\d)</b></td><td class=\"num set\">([0-9.]+)</td>"
                      r"<td>([^<]*)</td><td>[^<]*</td><td>([^<]*)</td>"
                      r"<td class=\"num\">x(\d+)</td>",
                      html)
    assert rows == [(p.id, f"{p.setting:.3f}", p.signal, f"{p.amplifier} {p.jack}", str(p.weight))
                    for p in net.pots]
    # P2 and P3 use the x10 input (section 5.3: theta and s_dot need the multiplication by 10).
    assert [r[0] for r in rows if r[4] == "10"] == ["P2", "P3"]


def test_pot_error_against_the_design():
    _, html, md = _render()
    # P1: realised -0.226 against -0.22571575 -> +0.13 %; P2: -2.67 against -2.67048449 -> -0.02 %.
    assert "| **P1** | **0.226** |" in md and "+0.13 %" in md
    assert "−0.02 %" in html


def test_sheet_has_every_part_a_lab_needs():
    net, html, md = _render()
    for heading in ("Design summary", "Pot settings", "External parts", "Amplifier assignments", "Wire list",
                    "Wiring diagram", "Procedure", "Predicted on the bench"):
        assert heading in html and f"## {heading}" in md
    # one procedure, in the machine's own words (the netlist's mode steps are not printed twice)
    assert "Mode and initial conditions" not in html and "Bench checklist" not in html
    for part in net.parts:
        assert f"| **{part.id}** | {part.fit} |" in md
    wires = wire_list(net)
    for n, (frm, to) in enumerate(wires, 1):
        assert f"| {n} | {frm} | {to} | ☐ |" in md
    assert "<svg" in html and "P5" in html.split("<svg", 1)[1]
    assert "POT SET" in html and "overload lamps" in html and "servo amplifier last" in html
    assert "HD (hold)" in html and "then back to IC" not in html
    # User text is escaped in HTML.
    assert "&lt;as wired&gt;" in html and "<as wired>" not in html


def test_sign_check_follows_u_equals_minus_K_x():
    """Each row moves a quantity the + way (the cart, the pendulum, a rate's test voltage, or an
    integrator's output through its IC jack) and u_c must go as u = -K x says: every gain of
    section 5.3 is negative, so u_c goes + for each sensor's path (the rate's while the pendulum
    moves) and - for the integral's, whose amplifier carries -int theta."""
    _, _, md = _render()
    rows = re.findall(r"^\| (P\d) \| ([^|]+) \| ([^|]+) \| ([^|]+) \| \*\*([^*]+)\*\* \|$", md, flags=re.MULTILINE)
    state = {"P1": ("s", 1), "P2": ("theta", 1), "P3": ("s_dot", 1), "P4": ("theta_dot", 1), "P5": ("int_theta", -1)}
    assert [r[0] for r in rows] == list(state)
    for pot, on, _, read, way in rows:
        name, polarity = state[pot]
        k = SUMMARY.K[SUMMARY.states.index(name)]
        assert way.startswith("+" if -k * polarity > 0 else "−"), (pot, way)
        assert on.strip() == pot and read.strip() == "u_c (A7)"
    moves = {r[0]: r[2] for r in rows}
    assert moves["P1"] == "move the cart toward +s by hand" and moves["P2"] == "lean the pendulum toward +s by hand"
    assert moves["P3"].startswith("s_dot input at +") and "(spare pot P6 at " in moves["P3"]
    assert moves["P4"].endswith("read while it moves") and moves["P5"].startswith("A1's IC jack at −")
    assert "Make positive" not in md


def test_same_inputs_same_bytes():
    _, html, md = _render()
    _, html2, md2 = _render()
    assert html == html2 and md == md2


def _pdf_pages(pdf: bytes) -> tuple[int, list[tuple[float, float]]]:
    """Page count and page sizes (pt) of a PDF, read from its page objects."""
    pages = len(re.findall(rb"/Type\s*/Page(?![a-zA-Z])", pdf))
    if pages == 0:  # page objects inside compressed object streams: use the page tree's count
        pages = max(int(c) for c in re.findall(rb"/Count\s+(\d+)", pdf))
    boxes = [tuple(float(v) for v in m.split()[2:4])
             for m in re.findall(rb"/MediaBox\s*\[([^\]]*)\]", pdf)]
    return pages, boxes


def test_html_prints_on_three_pages_that_fit_a4_and_letter(tmp_path, chromium):
    """A patch on one machine prints on three pages, as the README says (there with the static
    check and the bench prediction: tests/render/test_sheet_pages.py)."""
    _, html, _ = _render()
    page = tmp_path / "patch-sheet.html"
    page.write_text(html, encoding="utf-8")
    pages, boxes = _pdf_pages(chromium.print_pdf(page))
    assert pages == 3
    assert boxes
    for w, h in boxes:   # within A4 (210 x 297 mm) and Letter (215.9 x 279.4 mm)
        assert w <= 210 * MM + 0.5 and h <= 279.4 * MM + 0.5


def test_checklist_and_pot_reading_come_from_the_procedure_given():
    net = read_netlist(FIXTURE)
    tat = load_machine("the-analog-thing").procedure
    steps = [Step(text="Lock the <cart> of the {machine} at ±{reference_V} V."), *tat.checklist[1:]]
    procedure = tat.model_copy(update={"pot_reading": "vernier", "checklist": steps})
    html, md = render_sheet(net, _summary(net), wiring_svg(net), procedure)
    # the fixture is a GP-6 patch: its name and reference fill the placeholders
    assert "1. Lock the <cart> of the Comdyna GP-6 at ±10 V." in md
    assert "<li>Lock the &lt;cart&gt; of the Comdyna GP-6 at ±10 V.</li>" in html
    assert "Settings to the vernier resolution 0.001." in md and "Settings to the vernier resolution" in html
    assert "Servo amplifier powered off" not in md and "Settings to the dial" not in md
    # the sign table is on this sheet, so the checklist carries the sign step with the table, not without
    assert "check on the panel meter (the reading patched to the u socket)" in md
    assert "A1's IC input at −" in md and "IC jack" not in md  # in the procedure's own words
    assert "Check each sign with one feedback path at a time (all other coefficients at 0).\n" not in md


def test_an_edited_copy_of_a_shipped_design_is_named_with_its_file(tmp_path):
    """A copy that keeps a shipped design's name says which file it is; the shipped design, by name
    or by its own path, and a copy under a name of its own, go by their names."""
    from patchgen.inputs.spec import load_spec
    from patchgen.render.patchfiles import design_label
    from tests.cli_run import run_patchgen
    from tests.conftest import design_path

    text = design_path("bench-recommended").read_text()
    (tmp_path / "my-copy.toml").write_text(text.replace("theta weighted", "theta weighted, edited"))
    (tmp_path / "mine.toml").write_text(text.replace('name = "bench-recommended"', 'name = "mine"'))
    assert design_label(load_spec("bench-recommended")) == "bench-recommended"
    assert design_label(load_spec(str(design_path("bench-recommended")))) == "bench-recommended"
    assert design_label(load_spec(str(tmp_path / "mine.toml"))) == "mine"
    r = run_patchgen("patch", "./my-copy.toml", "--no-predict", "-o", "out", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    html, md = ((tmp_path / "out" / f).read_text() for f in ("patch-sheet.html", "patch-sheet.md"))
    assert "<title>Patch sheet: bench-recommended (from ./my-copy.toml)</title>" in html
    assert "# Patch sheet: bench-recommended (from ./my-copy.toml)" in md
    assert "| Design | bench-recommended (from ./my-copy.toml) |" in md
    assert '"design": "bench-recommended"' in (tmp_path / "out" / "netlist.json").read_text()  # the netlist as before
