"""A control weight per command volt squared (weights.R_V, as Quanser states its LQR weights):
the design is the one with R = R_V / K_U^2 per newton squared, to the last bit; R and R_V together,
or an R_V whose newton weight leaves the range, is one line naming weights.R_V."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from patchgen.design.lqg import design
from patchgen.design.weights import r_matrix
from patchgen.inputs.errors import InputError
from patchgen.inputs.resources import resolve
from patchgen.inputs.spec import DesignSpec, check_spec


def _spec(**weights) -> DesignSpec:
    data = tomllib.loads(resolve("design", "thesis-case1-noint").read_text())
    data["weights"] = {**{k: v for k, v in data["weights"].items() if k not in ("R", "R_V")}, **weights}
    spec = DesignSpec.model_validate(data)
    check_spec(spec)
    return spec


def test_a_weight_per_volt_is_the_weight_per_newton_over_k_u_squared():
    per_newton = _spec(R=1.0)
    K_U = per_newton.actuator.K_U
    per_volt = _spec(R_V=K_U**2)
    assert r_matrix(per_volt)[0, 0] == K_U**2 / K_U**2 == 1.0
    np.testing.assert_array_equal(design(per_volt).K, design(per_newton).K)
    q = _spec(R_V=0.02)  # Quanser's R = 0.02 V^-2
    assert r_matrix(q)[0, 0] == pytest.approx(0.02 / K_U**2, rel=1e-15)


@pytest.mark.parametrize("weights, field", [
    ({"R": 1.0, "R_V": 1.0}, "weights.R_V"),
    ({"R_V": 0.0}, "weights.R_V"),
    ({"R_V": 1e8 * 10.0**2 * 1e3}, "weights.R_V"),
    ({"R_V": 1e-7}, "weights.R_V"),  # in range per volt, below it once divided by K_U^2
    ({}, "weights.R"),
])
def test_a_weight_per_volt_it_cannot_take_is_one_line(weights, field):
    with pytest.raises(InputError) as exc:
        _spec(**weights)
    assert f": {field}: " in exc.value.line() and "\n" not in exc.value.line()
