"""Other realisations of a loop (A, B, C): random similarity transforms of a given condition number,
and the companion forms of a transfer function, as badly scaled as its coefficients."""

from __future__ import annotations

import numpy as np


def similarity(n: int, cond: float, seed: int) -> np.ndarray:
    """A random n x n matrix with singular values spread evenly in log from 1 to cond (a scalar of
    that size for n = 1): U diag(s) V^T with U, V random orthogonal, seeded."""
    if n == 1:
        return np.array([[cond]])
    rng = np.random.default_rng(seed)
    U, _ = np.linalg.qr(rng.standard_normal((n, n)))
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return U @ np.diag(np.logspace(0, np.log10(cond), n)) @ V.T


def similar(A, B, C, cond: float, seed: int):
    """(T^-1 A T, T^-1 B, C T) for a random T of condition number cond: the same loop."""
    A, B, C = np.atleast_2d(A), np.asarray(B, float).reshape(-1, 1), np.asarray(C, float).reshape(1, -1)
    T = similarity(A.shape[0], cond, seed)
    Ti = np.linalg.inv(T)
    return Ti @ A @ T, Ti @ B, C @ T


def companion(num, den):
    """The controllable companion form of num/den (den monic, num of lower degree): A's last row
    the coefficients, B = e_n, C the numerator's coefficients, lowest power first."""
    den = np.asarray(den, float)
    n = len(den) - 1
    A = np.eye(n, k=1)
    A[-1] = -den[:0:-1] / den[0]
    B = np.zeros((n, 1))
    B[-1, 0] = 1.0
    C = np.zeros((1, n))
    C[0, :len(num)] = np.asarray(num, float)[::-1] / den[0]
    return A, B, C


def observer_companion(num, den):
    """The observable companion form of num/den: the transpose of the controllable one."""
    A, B, C = companion(num, den)
    return A.T, C.T, B.T
