"""Machine profiles: the parts behind the panel, as the SPICE deck reads them."""

from __future__ import annotations

import pytest

from patchgen.profiles.machine import load_machine


@pytest.mark.parametrize("name", ["gp6", "the-analog-thing"])
def test_input_resistors_follow_the_weights(name):
    c = load_machine(name).components
    assert c.input_resistor_ohm(1) == c.input_resistor_x1_ohm
    assert c.input_resistor_ohm(10) == c.input_resistor_x10_ohm
    # each shipped machine's x10 input is a tenth of its x1 resistor (gain = feedback / input)
    assert c.input_resistor_x10_ohm == pytest.approx(c.input_resistor_x1_ohm / 10, rel=1e-12)
    assert c.input_resistor_x1_ohm == pytest.approx(c.feedback_resistor_ohm, rel=1e-12)
    # a weight the profile names no resistor for is the unit resistor divided by the weight
    assert c.input_resistor_ohm(5) == pytest.approx(c.input_resistor_x1_ohm / 5, rel=1e-15)
