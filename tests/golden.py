"""Comparing written output with a stored golden file: structure exactly, each number to what it
can honestly carry.

Floating-point results differ in their last digits across machines and library versions (BLAS,
LAPACK, numpy), and a figure computed from an ill-conditioned step (a gain on a nearly
uncontrollable mode) differs in more of them. So a golden file is never compared byte for byte,
nor every figure to one blanket tolerance: the outputs are computed again from the design's inputs
moved at rounding level (what another build of the same libraries does to them), and each number
may differ from its golden value by SAFETY times the largest change seen there, and never by less
than a floor (rtol, atol) far below what any figure is quoted to.
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from patchgen.design.precision import ROUNDING

# a number as text writes it: sign, digits, decimals, exponent
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
SAFETY = 10.0  # another machine may move a figure this many times more than the perturbations did
PERTURBED_SECTIONS = ("plant", "sensors", "actuator", "weights", "estimator")


def perturbed(spec, seed: int):
    """The spec with every float of its plant, sensors, actuator, weights and estimator moved by a
    few units in the last place (a section whose moved values its bounds refuse stays as it is)."""
    rng = np.random.default_rng(seed)

    def move(v):
        if isinstance(v, float) and not isinstance(v, bool):
            return v * (1.0 + ROUNDING * rng.uniform(-1.0, 1.0))
        if isinstance(v, dict):
            return {k: move(x) for k, x in v.items()}
        if isinstance(v, list):
            return [move(x) for x in v]
        return v

    data = spec.model_dump()
    for section in PERTURBED_SECTIONS:
        trial = dict(data, **{section: move(data[section])})
        try:
            type(spec).model_validate(trial)
        except ValueError:
            continue
        data = trial
    return type(spec).model_validate(data)


def spread(nominal: Any, others: list[Any], where: str = "$") -> Any:
    """The largest change of each float of ``nominal`` over ``others`` (same structure), as a tree
    of the same shape; a structural difference is an AssertionError (the output's shape itself
    would then depend on rounding)."""
    if isinstance(nominal, dict):
        return {k: spread(nominal[k], [o[k] for o in others], f"{where}.{k}") for k in nominal}
    if isinstance(nominal, list):
        assert all(len(o) == len(nominal) for o in others), f"{where}: length moves with rounding"
        return [spread(x, [o[i] for o in others], f"{where}[{i}]") for i, x in enumerate(nominal)]
    if isinstance(nominal, float):
        return max((abs(o - nominal) for o in others), default=0.0)
    assert all(o == nominal for o in others), f"{where}: {nominal!r} moves with rounding"
    return 0.0


def text_spread(nominal: str, others: list[str], where: str = "text") -> list[float]:
    """The largest change of each number in a text over the others (same words, same count)."""
    base = [float(x) for x in NUMBER.findall(nominal)]
    moved = [[float(x) for x in NUMBER.findall(o)] for o in others]
    assert all(len(m) == len(base) for m in moved), f"{where}: the count of numbers moves with rounding"
    return [max((abs(m[i] - b) for m in moved), default=0.0) for i, b in enumerate(base)]


def _allowed(want: float, rtol: float, atol: float, s: float) -> float:
    return atol + rtol * abs(want) + SAFETY * s


def assert_matches(got: Any, want: Any, rtol: float, atol: float, where: str = "$", spreads: Any = None) -> None:
    """Raise AssertionError at the first place where ``got`` and ``want`` differ: keys, lengths,
    strings, integers and booleans exactly; floats within ``atol + rtol |want| + SAFETY spread``
    (``spreads``: a tree shaped like ``want``, from :func:`spread`; None for none)."""
    if isinstance(want, dict):
        assert isinstance(got, dict), f"{where}: expected an object, got {type(got).__name__}"
        assert sorted(got) == sorted(want), f"{where}: keys {sorted(got)} != {sorted(want)}"
        for k in want:
            assert_matches(got[k], want[k], rtol, atol, f"{where}.{k}", None if spreads is None else spreads[k])
    elif isinstance(want, list):
        assert isinstance(got, list), f"{where}: expected a list, got {type(got).__name__}"
        assert len(got) == len(want), f"{where}: length {len(got)} != {len(want)}"
        for i, (g, w) in enumerate(zip(got, want)):
            assert_matches(g, w, rtol, atol, f"{where}[{i}]", None if spreads is None else spreads[i])
    elif isinstance(want, float) and not isinstance(want, bool):
        assert isinstance(got, (int, float)) and not isinstance(got, bool), f"{where}: {got!r} is not a number"
        assert math.isfinite(got) == math.isfinite(want), f"{where}: {got!r} != {want!r}"
        tol = _allowed(want, rtol, atol, spreads or 0.0)
        assert abs(got - want) <= tol, f"{where}: {got!r} != {want!r} (allowed {tol:.3g})"
    else:
        assert type(got) is type(want) and got == want, f"{where}: {got!r} != {want!r}"


def assert_text_matches(got: str, want: str, rtol: float, atol: float, where: str = "text",
                        spreads: list[float] | None = None) -> None:
    """Text equal to ``want`` but for its numbers, each within ``atol + rtol |want| + SAFETY
    spread`` (``spreads`` from :func:`text_spread`, one per number): the words, markup and layout
    exactly, the figures to what they carry."""
    got_words, want_words = NUMBER.split(got), NUMBER.split(want)
    got_nums, want_nums = NUMBER.findall(got), NUMBER.findall(want)
    assert len(got_nums) == len(want_nums), f"{where}: {len(got_nums)} numbers != {len(want_nums)}"
    for i, (g, w) in enumerate(zip(got_words, want_words)):
        assert g == w, f"{where}: text differs before number {i}: {g[-60:]!r} != {w[-60:]!r}"
    for i, (g, w) in enumerate(zip(got_nums, want_nums)):
        tol = _allowed(float(w), rtol, atol, spreads[i] if spreads else 0.0)
        assert abs(float(g) - float(w)) <= tol, f"{where}: number {i}: {g} != {w} (allowed {tol:.3g})"


PERTURBATIONS = 4  # perturbed recomputations per design


def patch_outputs(spec) -> dict[str, str]:
    """What `patchgen patch` writes for a spec, by file name (no bench prediction)."""
    from patchgen.bench.diagnosis import as_patched_on_bench
    from patchgen.design.lqg import design_on
    from patchgen.pipeline.scaling import scaled_patch
    from patchgen.profiles.bench import load_bench
    from patchgen.profiles.machine import load_machine
    from patchgen.render.patchfiles import patch_files

    machine, bench = load_machine(spec.machine), load_bench(spec.bench)
    d = design_on(spec, machine, bench)
    net = scaled_patch(d, machine, bench).netlist  # scaled for signal-to-noise, as every command builds it
    return patch_files(d, machine, net, judged=as_patched_on_bench(d, net, machine, bench))


def outputs_and_spreads(spec) -> tuple[dict[str, str], dict[str, Any]]:
    """A spec's patch files, and for each the spread of its numbers under PERTURBATIONS
    rounding-level moves of the inputs (netlist.json: a tree; text files: a list per number)."""
    import json

    files = patch_outputs(spec)
    others = [patch_outputs(perturbed(spec, seed)) for seed in range(PERTURBATIONS)]
    spreads: dict[str, Any] = {}
    for name, text in files.items():
        if name.endswith(".json"):
            spreads[name] = spread(json.loads(text), [json.loads(o[name]) for o in others], name)
        else:
            spreads[name] = text_spread(text, [o[name] for o in others], name)
    return files, spreads
