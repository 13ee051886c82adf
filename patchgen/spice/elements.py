"""The elements a SPICE deck is written from: node names, numbers, loaded pots and the smoothed
behavioural expressions (saturation bound, dead zone, limit) ngspice's Newton iteration can follow."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

# The actuator's dead zone, force limit and the track's limit switches are written with max/abs
# and their corners rounded (softplus) over this fraction of their size, so Newton's iteration sees
# continuous derivatives. (ngspice 39's B-source limit() silently evaluates to 0: not used.) With
# the feedback-bound amplifiers hard corners also run; the rounding is a cheap precaution.
SMOOTHING = 0.01
# Amplifier saturation: a feedback bound of this many times the feedback conductance, with its
# corner rounded over this fraction of the saturation voltage.
BOUND_STIFFNESS = 1.0e3
BOUND_SMOOTHING = 1.0e-3


def spice_name(name: str) -> str:
    """A SPICE-safe lower-case node or element suffix."""
    return re.sub(r"[^a-z0-9_]", "_", name.lower())


def num(x: float) -> str:
    """Full-precision number text for the deck (deterministic)."""
    return repr(float(x))


def pot_wiper_position(setting: float, pot_ohm: float, load_ohm: float) -> float:
    """Wiper position a (0..1) whose LOADED ratio equals ``setting``.

    Pots are set in POT SET mode with the load connected, so the dial setting k is the ratio
    v_wiper/v_top with the load R_L (the amplifier's input resistor, to a virtual ground) across
    the lower part a*R_p. Solving k = (a R_p || R_L) / ((1 - a) R_p + a R_p || R_L) for a gives
    k R_p a^2 + (R_L - k R_p) a - k R_L = 0; the root is written in its cancellation-free form.
    """
    if not 0.0 <= setting <= 1.0:
        raise ValueError(f"pot setting {setting} outside 0..1")
    if setting == 0.0:
        return 0.0
    k, rp, rl = setting, pot_ohm, load_ohm
    b = rl - k * rp
    disc = math.sqrt(b * b + 4.0 * k * k * rp * rl)
    a = 2.0 * k * rl / (b + disc) if b >= 0 else (disc - b) / (2.0 * k * rp)
    return min(max(a, 0.0), 1.0)


def loaded_ratio(position: float, pot_ohm: float, load_ohm: float) -> float:
    """v_wiper/v_top of a pot at wiper position a with a load R_L on the wiper (to ground)."""
    lower = position * pot_ohm
    if lower == 0.0:
        return 0.0
    par = lower * load_ohm / (lower + load_ohm)
    return par / ((1.0 - position) * pot_ohm + par)


def bound(out: str, vsat: float, r_feedback: float) -> str:
    """Current of a feedback limiter from the output into the summing junction: zero inside
    +/-vsat, a conductance BOUND_STIFFNESS times the feedback resistor's beyond it (corners rounded
    over BOUND_SMOOTHING of vsat). The amplifier stays in its linear region and the summing
    junction at virtual ground, so a saturated amplifier neither winds up nor stalls ngspice's
    Newton iteration (an output clipped inside the op-amp, e.g. by tanh, does both)."""
    w, v, g = BOUND_SMOOTHING * vsat, num(vsat), num(BOUND_STIFFNESS / r_feedback)
    return f"{g}*({softplus(f'({out}-{v})', w)}-{softplus(f'(-({out})-{v})', w)})"


def softplus(x: str, width: float) -> str:
    """A smooth max(x, 0): max(x, 0) + w ln(1 + exp(-|x|/w)), exact beyond a few widths."""
    w = num(width)
    return f"(max({x},0)+{w}*ln(1+exp(-abs({x})/{w})))"


def dead_zone(x: str, half_width: float) -> str:
    """Smoothed dead zone: 0 inside +/-half_width, x -/+ half_width outside."""
    w, dz = SMOOTHING * half_width, num(half_width)
    return f"{softplus(f'({x}-{dz})', w)}-{softplus(f'(-({x})-{dz})', w)}"


def clamp(x: str, limit: float) -> str:
    """Smoothed limit to +/-limit."""
    w, lim = SMOOTHING * limit, num(limit)
    return f"{x}-{softplus(f'({x}-{lim})', w)}+{softplus(f'(-({x})-{lim})', w)}"


@dataclass
class DeckLines:
    """A deck being written: its lines, its noise sources' samples (name, step, values) from
    one seeded generator, and the initial voltages of its capacitor nodes."""

    rng: np.random.Generator
    lines: list[str] = field(default_factory=list)
    noise: list[tuple[str, float, np.ndarray]] = field(default_factory=list)
    ics: dict[str, float] = field(default_factory=dict)

    def add(self, *lines: str) -> None:
        """Append deck lines."""
        self.lines.extend(lines)

    def comment(self, text: str) -> None:
        """Append a comment line."""
        self.lines.append(f"* {text}")


def state_integrator(d: DeckLines, node: str, rate_expr: str, x0: float) -> None:
    """dx/dt = rate: a behavioural current into a 1 F capacitor (node voltage = x)."""
    d.add(f"B_{node} 0 {node} I = {rate_expr}", f"C_{node} {node} 0 1")
    d.ics[node] = float(x0)
