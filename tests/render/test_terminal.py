"""The terminal's pieces on their own: signed zeros, the compact table at 80 columns, the sweep's
gain columns split to fit and its pots summed up, the refusals one line per kind."""

from __future__ import annotations

import io

import pytest
from rich.console import Console

from patchgen.render.recommend_view import ranked_below
from patchgen.render.refusals import kind, summary
from patchgen.render.sweep_view import _pots, _split
from patchgen.render.terminal import add_row, figure, number, show, table, text, tidy


@pytest.mark.parametrize("raw, shown", [
    ("-0.000 1/s", "0.000 1/s"), ("−0.00 %", "0.00 %"), ("-0.0000", "0.0000"), ("+0.0", "0.0"), ("[-0]", "[0]"),
    ("-0.05", "-0.05"), ("1e-05", "1e-05"), ("5-95%: 0.0-0.0", "5-95%: 0.0-0.0"), ("-10.0", "-10.0"),
    ("x-0.0", "x-0.0"), ("+0.126 %", "+0.126 %"), ("-0.00e+00", "0.00e+00"),
])
def test_a_zero_prints_without_a_sign(raw, shown):
    assert tidy(raw) == shown


def test_figures():
    assert figure(-1e-9, "{:.3f}") == "0.000" and figure(None) == "-" and figure(float("inf")) == "inf"
    assert figure(-2.5, "{:+.1f}") == "-2.5"


def test_a_table_keeps_its_numbers_whole_and_wraps_its_words():
    t = table("a title " * 20, text("words"), number("figure"))
    add_row(t, "a long description that has to wrap " * 4, "-12345.678901")
    add_row(t, "short", "-0.000")
    console = Console(file=io.StringIO(), width=80, record=True)
    show(console, t)
    out = console.export_text()
    assert max(len(x) for x in out.splitlines()) <= 80 and "…" not in out
    assert "-12345.678901" in out and "-0.000" not in out
    assert out.splitlines()[0].startswith("a title a title")  # the title at the console's width


def test_the_sweep_splits_its_gains_only_where_they_would_not_fit():
    states = ["s", "theta", "s_dot", "theta_dot", "int_s", "int_theta", "actuator"]
    gains = [["-249.4119"] * 7]
    assert _split(states, gains, ["b_VF +10%"], 160) == [list(range(7))]
    parts = _split(states, gains, ["b_VF +10%"], 80)
    assert len(parts) == 2 and sum(parts, []) == list(range(7))
    assert all(9 + sum(2 + 9 for _ in p) <= 80 for p in parts)


def test_the_sweep_names_the_pots_that_move_most_and_counts_the_rest():
    changes = {f"P{i}": (0.5, 0.5 + i / 100) for i in range(1, 10)}
    cell = _pots(changes, 69)
    assert cell.split(",\n")[0].startswith("P6 0.500→0.560")  # those that move most, in the patch's order
    assert "P9 0.500→0.590" in cell and "P1 " not in cell and cell.endswith("and 5 more")
    assert all(len(line) <= 69 for line in cell.splitlines())
    assert _pots({}, 69) == "none"


def test_refusals_are_one_line_per_kind():
    short = ("the patch needs at least {a} amplifiers ({i} integrators) and {p} pots; the Comdyna GP-6 x2 "
             "(slaved) has 16 amplifiers (8 integrators) and 16 pots")
    refused = [("Kalman", short.format(a=6, i=5, p=36)),
               ("order 5", "no realisation fits 2 unit(s) of the Comdyna GP-6; the smallest tried: "
                + short.format(a=6, i=5, p=23)),
               ("order 9", short.format(a=20, i=9, p=40)),
               ("order 2", "no form of the order-2 compensator keeps the loop stable"),
               ("order 1", "no form of the order-1 compensator keeps the loop stable")]
    lines = summary(refused)
    assert lines == [
        "2 candidates do not fit: the patch needs more pots than the Comdyna GP-6 x2 (slaved) has (16)",
        "2 candidates not run (order 2; 1 more like it): no form of the order-2 compensator keeps the loop stable",
        "1 candidate does not fit: the patch needs more amplifiers, integrators and pots than the Comdyna "
        "GP-6 x2 (slaved) has (16, 8, 16)",
    ]
    assert kind("something else 3") == kind("something else 4")


def test_the_candidates_ranked_below_are_counted_by_verdict():
    rows = [{"decision": "fails", "bench_loop": "unstable"}] * 3 + [{"decision": "undecided", "bench_loop": "stable"}]
    assert ranked_below(rows) == ("4 more ranked below, by verdict (wired loop on the bench): 3 fail (unstable), "
                                  "1 undecided (stable)")
    assert ranked_below([]) == ""
