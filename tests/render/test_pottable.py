"""The pot table on its own: CSV read back, each row against the pot it describes, the terminal table."""

from __future__ import annotations

import csv
import io

import pytest
from rich.console import Console

from patchgen.design.lqg import design_on
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.render.pottable import COLUMNS, pot_rows, pot_table, pots_csv

GP6 = load_machine("gp6")


@pytest.fixture(scope="module")
def net():
    spec = load_spec("bench-recommended")
    return build_patch(design_on(spec, GP6, load_bench(spec.bench)), GP6)


def _with_zero_coefficient(net):
    """The netlist with its first pot wired for a coefficient of 0 (an error with no percentage)."""
    pots = [net.pots[0].model_copy(update={"coefficient": 0.0}), *net.pots[1:]]
    return net.model_copy(update={"pots": pots})


def test_csv_reads_back_to_the_rows(net):
    text = pots_csv(net)
    reader = csv.DictReader(io.StringIO(text))
    assert tuple(reader.fieldnames) == COLUMNS
    back = list(reader)
    assert back == [{k: str(v) for k, v in row.items()} for row in pot_rows(net)]
    assert [r["pot"] for r in back] == [p.id for p in net.pots] == ["P1", "P2", "P3", "P4", "P5", "P6", "P7"]
    assert text.endswith("\n") and "\r" not in text


def test_each_row_is_its_pot(net):
    for p, row in zip(net.pots, pot_rows(net), strict=True):
        setting, weight = float(row["setting"]), int(row["weight"])
        assert setting == pytest.approx(p.setting, abs=5e-4)  # three decimals on the dial
        # realised = sign x setting x weight (the netlist's definition), to the printed digits
        assert abs(float(row["realized"])) == pytest.approx(setting * weight, rel=1e-5)
        want_pct = 100 * (float(row["realized"]) / float(row["coefficient"]) - 1)
        assert float(row["error_pct"]) == pytest.approx(want_pct, abs=2e-3)
        assert (row["amplifier"], row["input"], row["signal"]) == (p.amplifier, p.jack, p.signal)
    # by hand (the recommended patch on the GP-6): theta into A7 through a x10 input; the actuator lag
    # of 0.2 s as an integrator whose own output comes back through P1 at 0.5 on a x10 input (T/tau = 5)
    p4 = pot_rows(net)[3]
    assert (p4["setting"], p4["signal"], p4["weight"], p4["realized"]) == ("0.915", "theta", 10, "9.15")
    own = next(r for r in pot_rows(net) if r["amplifier"] == "A1" and r["signal"] == "actuator")
    assert (own["setting"], own["weight"], own["realized"]) == ("0.500", 10, "-5")


def test_a_coefficient_of_zero_has_no_error_percentage(net):
    odd = _with_zero_coefficient(net)
    assert pot_rows(odd)[0]["error_pct"] == "inf"
    assert "\nP1,0.500,-u_c,A1,x10a,10,0,5,inf,,\n" in pots_csv(odd)
    console = Console(file=io.StringIO(), width=200, record=True)
    console.print(pot_table(odd, GP6.procedure.pot_setting))
    p1 = next(line for line in console.export_text().splitlines() if "P1" in line)
    assert p1.rstrip().rstrip("│").strip().endswith("n/a")


def test_terminal_table_names_the_machine_and_how_pots_are_set(net):
    t = pot_table(net, "set in POT SET, load connected")
    assert t.row_count == len(net.pots)
    assert t.title == "Pot settings for bench-recommended on the Comdyna GP-6 (set in POT SET, load connected)"
    console = Console(file=io.StringIO(), width=200, record=True)
    console.print(t)
    text = console.export_text()
    assert "A7 x10a " in text and "(x10)" not in text and "-0.232 %" in text  # x10a says its weight


def test_the_terminal_names_the_weight_of_a_jack_whose_name_does_not(net):
    """A jack named for its weight (x10a) stands alone; one that is not keeps the weight beside it."""
    first = net.pots[0]
    odd = net.model_copy(update={"pots": [first.model_copy(update={"jack": "in1"}), *net.pots[1:]]})
    console = Console(file=io.StringIO(), width=80, record=True)
    console.print(pot_table(odd, "x"))
    assert f"{first.amplifier} in1 (x{first.weight})" in console.export_text()


def test_a_machine_named_with_its_article_is_not_given_another(net):
    """THE ANALOG THING's name includes its article: the title and the static check's caption say it once."""
    from patchgen.patch.static_check import static_check

    tat = load_machine("the-analog-thing")
    named = net.model_copy(update={"machine_name": tat.name})
    assert pot_table(named, "x").title.startswith("Pot settings for bench-recommended on THE ANALOG THING (")
    tat_net = build_patch(design_on(load_spec("bench-recommended"), tat, load_bench("uw-1991")), tat)
    unseen = " ".join(static_check(tat_net, tat).unchecked)
    assert "THE ANALOG THING cannot" in unseen and "the THE" not in unseen
