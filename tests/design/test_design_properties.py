"""Property tests: for random stabilisable cart-pendulums and weights the design is a true LQR."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from patchgen.design.lqg import design
from patchgen.inputs.spec import DesignSpec, check_spec

pos = lambda lo, hi: st.floats(lo, hi, allow_nan=False, allow_infinity=False).map(lambda x: 0.0 if x < 1e-8 else x)


def hamiltonian_lqr(A, B, Q, R):
    """The LQR gain from the stable eigenvectors [X1; X2] of [[A, -B R^-1 B'], [-Q, -A']]:
    S = X2 X1^-1 (a different route from the Schur-based Riccati solver patchgen calls)."""
    n = A.shape[0]
    H = np.block([[A, -B @ np.linalg.solve(R, B.T)], [-Q, -A.T]])
    w, V = np.linalg.eig(H)
    X = V[:, np.argsort(w.real)[:n]]
    S = np.real(X[n:] @ np.linalg.inv(X[:n]))
    return np.linalg.solve(R, B.T @ (S + S.T) / 2)


@st.composite
def specs(draw):
    data = {
        "name": "random",
        "plant": {"M": draw(pos(0.5, 10)), "m": draw(pos(0.05, 2)), "l": draw(pos(0.1, 1.5)),
                  "g": 9.807, "b_VF": draw(pos(0, 10)), "c": draw(pos(0, 0.01))},
        "sensors": {"s": 5.0, "theta": 4.19, "s_dot": 0.5941},
        "actuator": {"model": draw(st.sampled_from(["gain", "lag"])), "K_U": 14.01, "tau": draw(pos(0.01, 0.5))},
        "weights": {"Q": {"s": draw(pos(0.1, 100)), "theta": draw(pos(0.1, 1000)),
                          "s_dot": draw(pos(0, 100)), "theta_dot": draw(pos(0, 100))},
                    "R": draw(pos(0.01, 10))},
        "integrators": {"int_s": draw(st.booleans()), "int_theta": draw(st.booleans())},
    }
    spec = DesignSpec.model_validate(data)
    check_spec(spec)
    return spec


@settings(max_examples=40, deadline=None)
@given(specs())
def test_lqr_is_optimal_and_stabilising(spec):
    d = design(spec)
    A, B, Q, R, K, S = d.model.A, d.model.B, d.Q, d.R, d.K, d.S
    # closed loop stable
    assert np.max(np.linalg.eigvals(A - B @ K).real) < 0
    # Riccati residual small relative to the terms
    res = A.T @ S + S @ A - S @ B @ np.linalg.solve(R, B.T @ S) + Q
    scale = max(1.0, np.abs(A.T @ S).max(), np.abs(Q).max())
    assert np.abs(res).max() < 1e-6 * scale
    # the same K by another algorithm: the stable invariant subspace of the Hamiltonian matrix
    K2 = hamiltonian_lqr(A, B, Q, R)
    np.testing.assert_allclose(K, K2, rtol=1e-5, atol=1e-7 * np.abs(K2).max())
    # LQR guarantees: phase margin >= 60 deg, upper gain margin infinite, lower at most 1/2
    m = d.lqr_margins
    assert m.stable and m.upper_gm is None
    assert m.pm_deg >= 60 - 1e-6
    assert m.lower_gm is None or m.lower_gm <= 0.5 + 1e-9


@settings(max_examples=20, deadline=None)
@given(st.dictionaries(st.sampled_from(["s", "theta", "s_dot", "theta_dot"]), pos(0.01, 5), min_size=4),
       pos(0.5, 20))
def test_bryson_weights_are_inverse_squares(sigmas, umax):
    spec = DesignSpec.model_validate({
        "name": "b", "plant": {"M": 3.552, "m": 0.324, "l": 0.429, "b_VF": 2.5775, "c": 0.001},
        "sensors": {"s": 5.0, "theta": 4.19, "s_dot": 0.5941}, "actuator": {"K_U": 14.01},
        "weights": {"bryson": {**sigmas, "u": umax}}})
    check_spec(spec)
    d = design(spec)
    for i, s in enumerate(d.states):
        assert d.Q[i, i] == np.float64(1.0) / sigmas[s] ** 2
    assert d.R[0, 0] == 1.0 / umax**2
