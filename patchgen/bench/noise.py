"""Counter-based Gaussian noise for the blocked kernel (patchgen.bench.kernel), drawn inside its loop
for all lanes at once: a run's noise is a pure function of its key and of (step, channel), so it
is the same whatever the block, the lane, the thread or the order.

Philox4x32-10 (Salmon et al., "Parallel random numbers: as easy as 1, 2, 3", SC 2011) with the
run's key and counter (step, channel group, attempt, domain) gives the bits; the Marsaglia-Tsang
ziggurat makes each 32-bit word normal: 10 bits pick one of 1024 layers, 1 the sign, 21 the
abscissa (a resolution of 5e-7 of the layer's width). A word outside its layer's inner rectangle
(0.43 % of them; 1.5 % with 256 layers, where the refused words cost more than the rest) takes
the wedge or tail test with further counters of its step and channel.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

_JIT = {"cache": True, "error_model": "numpy"}  # as patchgen.bench.kernel's

_M0, _M1 = np.uint64(0xD2511F53), np.uint64(0xCD9E8D57)
_W0, _W1 = np.uint64(0x9E3779B9), np.uint64(0xBB67AE85)
_LO, _S32 = np.uint64(0xFFFFFFFF), np.uint64(32)
_ZERO, _ONE = np.uint64(0), np.uint64(1)
_LAYER_BITS = 10
_J_BITS = 32 - _LAYER_BITS - 1
_LAYER, _SIGN_SHIFT, _J_SHIFT = np.uint64(2**_LAYER_BITS - 1), np.uint64(_LAYER_BITS), np.uint64(_LAYER_BITS + 1)
WORDS = 4  # normals per Philox call: channels are drawn in groups of four


def _ziggurat(layers: int = 2**_LAYER_BITS, r: float = 4.038849846109505):
    """Layer edges x_0 > x_1 = r > ... > x_layers = 0 of equal area v under f = exp(-x^2/2)
    (layer 0: the rectangle below f(r), x_0 = v / f(r), plus the tail), r being the edge at which
    that many layers close at the top (found by bisection; tests/bench/test_kernel.py checks it); and
    per layer: w (x = j w for a _J_BITS-bit j), k (j < k is under the curve at every height of the
    layer), f at its outer and inner edge."""
    f = lambda x: math.exp(-0.5 * x * x)
    v = r * f(r) + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2))
    x = [v / f(r), r]
    for _ in range(layers - 2):
        x.append(math.sqrt(-2.0 * math.log(f(x[-1]) + v / x[-1])))
    x = np.array(x + [0.0])
    fx = np.exp(-0.5 * x * x)
    k = np.floor(x[1:] / x[:-1] * 2.0**_J_BITS).astype(np.uint64)
    return x, x[:-1] / 2.0**_J_BITS, k, fx[:-1], fx[1:]


ZIGGURAT_EDGES, _ZW, _ZK, _ZF_OUT, _ZF_IN = _ziggurat()
_ZR = float(ZIGGURAT_EDGES[1])


@nb.njit(inline="always", **_JIT)
def philox(c0, c1, c2, c3, k0, k1):
    """Philox4x32-10 of counter (c0..c3) and key (k0, k1): uint64 values holding 32-bit words."""
    for i in range(10):
        if i > 0:
            k0 = (k0 + _W0) & _LO
            k1 = (k1 + _W1) & _LO
        p0 = _M0 * c0
        p1 = _M1 * c2
        c0, c1, c2, c3 = (p1 >> _S32) ^ c1 ^ k0, p1 & _LO, (p0 >> _S32) ^ c3 ^ k1, p0 & _LO
    return c0, c1, c2, c3


@nb.njit(inline="always", **_JIT)
def _zig_fast(word):
    """A normal from the inner rectangle of the layer a 32-bit word picks: (z, accepted)."""
    idx = word & _LAYER
    j = word >> _J_SHIFT
    z = np.float64(j) * _ZW[idx]
    return (-z if (word >> _SIGN_SHIFT) & _ONE else z), j < _ZK[idx]


@nb.njit(**_JIT)
def _zig_slow(word, n, ch, k0, k1):
    """A word the inner rectangles refused: wedge or tail test, then fresh words from counters
    (n, ch, attempt, 1) until one is accepted."""
    attempt = _ZERO
    while True:
        idx = word & _LAYER
        j = word >> _J_SHIFT
        neg = (word >> _SIGN_SHIFT) & _ONE
        x = np.float64(j) * _ZW[idx]
        if j < _ZK[idx]:
            return -x if neg else x
        attempt += _ONE
        o0, o1, o2, _ = philox(n, ch, attempt, _ONE, k0, k1)
        u1 = (np.float64(o1) + 0.5) * 2.0**-32
        u2 = (np.float64(o2) + 0.5) * 2.0**-32
        if idx == 0:  # the tail beyond r (Marsaglia 1964)
            a = -math.log(u1) / _ZR
            if -2.0 * math.log(u2) > a * a:
                return -(_ZR + a) if neg else _ZR + a
        elif _ZF_OUT[idx] + u1 * (_ZF_IN[idx] - _ZF_OUT[idx]) < math.exp(-0.5 * x * x):
            return -x if neg else x
        word = o0


@nb.njit(**_JIT)
def fill_normals(n, k0, k1, z, words, channels):
    """Standard normals of step n for the first ``channels`` channels (rows) and every lane
    (column) of z, whose rows are a whole number of groups of WORDS (the rows past ``channels``
    are left as they are: nothing reads them). k0, k1: the lanes' keys (uint64); words: scratch
    (WORDS, lanes) uint64. Loops kept apart (bits; inner rectangles; the rare rest) so that each
    vectorises."""
    c0 = np.uint64(n)
    for g in range(z.shape[0] // WORDS):
        c1 = np.uint64(g)
        for l in range(k0.shape[0]):
            words[0, l], words[1, l], words[2, l], words[3, l] = philox(c0, c1, _ZERO, _ZERO, k0[l], k1[l])
        for w in range(min(WORDS, channels - g * WORDS)):
            ch = g * WORDS + w
            refused = 0
            for l in range(k0.shape[0]):
                z[ch, l], accepted = _zig_fast(words[w, l])
                refused += not accepted
            if refused:
                for l in range(k0.shape[0]):
                    if not _zig_fast(words[w, l])[1]:
                        z[ch, l] = _zig_slow(words[w, l], c0, np.uint64(ch), k0[l], k1[l])


@nb.njit(**_JIT)
def run_normals(key0, key1, n_steps, nch):
    """One run's normals, (n_steps + 1, nch): exactly those the engine draws for that key."""
    k0 = np.full(1, np.uint64(key0))
    k1 = np.full(1, np.uint64(key1))
    rows = (nch + WORDS - 1) // WORDS * WORDS
    z = np.empty((rows, 1))
    words = np.empty((WORDS, 1), dtype=np.uint64)
    out = np.empty((n_steps + 1, nch))
    for n in range(n_steps + 1):
        fill_normals(n, k0, k1, z, words, nch)
        out[n] = z[:nch, 0]
    return out
