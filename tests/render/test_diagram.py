"""The SVG wiring diagram: parses, shows every pot (with its setting) and amplifier, same bytes; one
page per unit of slaved units."""

import json
import subprocess
import sys
import unicodedata
import xml.etree.ElementTree as ET
from pathlib import Path

from patchgen.patch.netlist import Netlist, read_netlist
from patchgen.render.diagram import wiring_diagram, wiring_svg
from patchgen.render.diagram_pages import MM_PER_PT, diagram_pages, svg_size_mm
from patchgen.render.diagram_symbols import quantity_label

FIXTURE = Path(__file__).parents[1] / "fixtures" / "thesis-ch5.netlist.json"
SVG_NS = "{http://www.w3.org/2000/svg}"


def _texts(svg: str) -> list[str]:
    root = ET.fromstring(svg)
    assert root.tag == SVG_NS + "svg"
    return ["".join(t.itertext()) for t in root.iter(SVG_NS + "text")]


def test_svg_shows_every_pot_with_its_setting_and_every_amplifier():
    net = read_netlist(FIXTURE)
    texts = _texts(wiring_svg(net))
    for amp in net.amplifiers:
        assert amp.id in texts
    for pot in net.pots:
        assert pot.id in texts
    # Settings as the fixture gives them, to the dial resolution 0.001.
    for setting in ("0.226", "0.267", "0.271", "0.599", "0.001"):
        assert setting in texts
    # Sensors named on the left, the control voltage on the right.
    for name in ("s", "θ", "ds/dt", "u_c"):
        assert name in texts


def test_svg_writes_the_input_weights_inside_the_amplifiers():
    net = read_netlist(FIXTURE)
    texts = _texts(wiring_svg(net))
    # A6 has one x1 and two x10 inputs, A1, A5 and A7 five x1 inputs in all (fixture).
    assert texts.count("10") == 2
    assert texts.count("1") == 6


def test_svg_marks_integrator_ic_and_differentiator():
    texts = _texts(wiring_svg(read_netlist(FIXTURE)))
    assert "IC 0 V" in texts          # A1, ic_V = 0 in the fixture
    assert "d/dt" in texts            # A5 is the differentiator
    assert "−∫θ" in texts and "−dθ/dt" in texts   # what A1 and A5 carry, with sign


def test_same_netlist_same_bytes_also_in_a_fresh_process():
    net = read_netlist(FIXTURE)
    first = wiring_svg(net)
    assert wiring_svg(net) == first
    code = ("import sys; from patchgen.render.diagram import wiring_svg; from patchgen.patch.netlist import "
            f"read_netlist; sys.stdout.write(wiring_svg(read_netlist({str(FIXTURE)!r})))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).parents[2])
    assert out.stdout == first


def _two_unit_netlist() -> Netlist:
    """The fixture duplicated on a second unit, with feedback between the units."""
    data = json.loads(FIXTURE.read_text())
    amps, pots = [], []
    for unit in ("U1", "U2"):
        for a in json.loads(FIXTURE.read_text())["amplifiers"]:
            a["id"] = f"{unit}.{a['id']}"
            for inp in a["inputs"]:
                if inp["source"].startswith("A"):
                    inp["source"] = f"{unit}.{inp['source']}"
                if inp["pot"]:
                    inp["pot"] = f"{unit}.{inp['pot']}"
            amps.append(a)
        for p in json.loads(FIXTURE.read_text())["pots"]:
            p["id"] = f"{unit}.{p['id']}"
            p["amplifier"] = f"{unit}.{p['amplifier']}"
            if p["source"].startswith("A"):
                p["source"] = f"{unit}.{p['source']}"
            pots.append(p)
    # A feedback path: U1.A1 also integrates U2.A7's output (a back edge in the layout).
    amps[0]["inputs"].append({"jack": "x1b", "pot": None, "source": "U2.A7", "weight": 1})
    data.update(amplifiers=amps, pots=pots, units=2)
    data["output"]["source"] = "U2.A7"
    return Netlist.model_validate(data)


def test_two_unit_netlist_with_feedback_draws_every_element():
    net = _two_unit_netlist()
    svg = wiring_svg(net)
    texts = _texts(svg)
    assert len(net.amplifiers) == 8 and len(net.pots) == 10
    for element in [a.id for a in net.amplifiers] + [p.id for p in net.pots]:
        assert element in texts
    assert wiring_svg(net) == svg


def test_quantity_labels():
    assert quantity_label("theta_dot") == "dθ/dt"
    assert quantity_label("s_dot") == "ds/dt"
    assert quantity_label("int_theta") == "∫θ"
    assert quantity_label("xhat_s") == "est. s"
    assert quantity_label("what_theta_dot") == "est. dθ/dt"
    assert quantity_label("z_actuator") == "z(actuator)"
    assert quantity_label("partial z_theta_dot") == "partial z(dθ/dt)"
    assert quantity_label("u_c") == "u_c"
    # no combining marks: every character stands on its own
    names = ("theta_dot", "s_dot", "xhat_theta_dot", "z_theta_dot", "what_actuator", "int_s")
    assert not any(unicodedata.combining(c) for q in names for c in quantity_label(q))


def test_one_machine_is_one_page_the_whole_diagram():
    net = read_netlist(FIXTURE)
    [(caption, svg)] = diagram_pages(net)
    assert svg == wiring_svg(net)
    assert caption == f"{net.design} on {net.machine_name}"


def test_a_diagram_measured_before_it_is_rendered_has_the_size_its_svg_states():
    """diagram_pages measures a diagram without rendering it (one too large for a page is drawn
    again in parts): the size it reads is the SVG's own, and the SVG is the same after it."""
    for net in (read_netlist(FIXTURE), _two_unit_netlist()):
        whole = wiring_diagram(net)
        width, height = whole.size_pt
        assert svg_size_mm(whole.svg) == (width * MM_PER_PT, height * MM_PER_PT)
        assert whole.svg == wiring_svg(net)
        assert diagram_pages(net, whole) == diagram_pages(net)


def test_slaved_units_are_one_page_each_with_flags_between_them():
    net = _two_unit_netlist()
    pages = diagram_pages(net)
    assert [c.split()[:4] for c, _ in pages] == [["Unit", "U1", "of", "2:"], ["Unit", "U2", "of", "2:"]]
    first, second = (_texts(svg) for _, svg in pages)
    # each unit's own amplifiers as on its panel; U2.A7's output feeds U1.A1 and leaves for the servo
    assert {"A1", "A5", "A6", "A7"} <= set(first) and "U1.A1" not in first
    assert "to U1.A1 x1b" in second and "from U2.A7" in first
    assert "to servo" in second and "to servo" not in first
    assert pages == diagram_pages(net)


def test_drawing_leaves_schemdraws_settings_as_it_found_them():
    """The diagram's clip numbering, text mode, font and line width hold for its own drawing only."""
    from schemdraw.schemdraw import schemdrawstyle

    from patchgen.render.schematic import svg_backend

    text_mode, style = svg_backend.config.text, dict(schemdrawstyle)
    svg_backend.Figure.total_clips = 7
    try:
        svg = wiring_svg(read_netlist(FIXTURE))
        assert svg_backend.Figure.total_clips == 7
        assert svg == wiring_svg(read_netlist(FIXTURE))  # clip ids counted from 0 each time
        assert svg_backend.config.text == text_mode
        assert schemdrawstyle == style
    finally:
        svg_backend.Figure.total_clips = 0
