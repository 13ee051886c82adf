"""The external parts a patch needs beyond the machine's own: one list for the sheet, the netlist
and the SPICE deck.

A GP-6 (and THE ANALOG THING) has input resistors, feedback resistors and integrating capacitors
behind its panel, and pots; what it lacks is patched with external parts:

- a **differentiator**: on each input, a capacitor C = w T_d / R_f from the input's cord to a
  series resistor R_s = rolloff / C into the amplifier's summing junction (the resistor caps the
  high-frequency gain: the first-order roll-off); the amplifier's own feedback resistor R_f closes
  it, so T_d = R_f C / w;
- a **lag** that could not be built from an integrator and a pot (patchgen.patch.realization.
  lag_block): an amplifier patched as a summer (feedback resistor R_f) with a capacitor
  C = tau / R_f across its feedback, summing junction to output.

Each part gets its nominal value and a stock fit: the nearest E96 resistor (1 % metal film; at
most 1.5 % off), or one E12 capacitor, or two in parallel when one is more than 1 % off (then
within 2 %). The
netlist's element values stay the design's; a fit's error and the parts' tolerance (machine
profile ``components``) are stated beside them.
"""

from __future__ import annotations

import math

from patchgen.patch.netlist import Netlist, Part
from patchgen.patch.reading import read
from patchgen.profiles.machine import MachineProfile

# IEC 60063 preferred numbers, one decade
E12 = (1.0, 1.2, 1.5, 1.8, 2.2, 2.7, 3.3, 3.9, 4.7, 5.6, 6.8, 8.2)
CAPACITOR_FIT = 0.01  # a capacitor fit within this of the nominal needs no second part
E96 = (1.00, 1.02, 1.05, 1.07, 1.10, 1.13, 1.15, 1.18, 1.21, 1.24, 1.27, 1.30, 1.33, 1.37, 1.40, 1.43,
       1.47, 1.50, 1.54, 1.58, 1.62, 1.65, 1.69, 1.74, 1.78, 1.82, 1.87, 1.91, 1.96, 2.00, 2.05, 2.10,
       2.15, 2.21, 2.26, 2.32, 2.37, 2.43, 2.49, 2.55, 2.61, 2.67, 2.74, 2.80, 2.87, 2.94, 3.01, 3.09,
       3.16, 3.24, 3.32, 3.40, 3.48, 3.57, 3.65, 3.74, 3.83, 3.92, 4.02, 4.12, 4.22, 4.32, 4.42, 4.53,
       4.64, 4.75, 4.87, 4.99, 5.11, 5.23, 5.36, 5.49, 5.62, 5.76, 5.90, 6.04, 6.19, 6.34, 6.49, 6.65,
       6.81, 6.98, 7.15, 7.32, 7.50, 7.68, 7.87, 8.06, 8.25, 8.45, 8.66, 8.87, 9.09, 9.31, 9.53, 9.76)


def _decade(value: float) -> tuple[float, float]:
    """(mantissa in [1, 10), power of ten) of a positive value."""
    p = math.floor(math.log10(value))
    m = value / 10 ** p
    if m >= 10 - 1e-9:
        m, p = m / 10, p + 1
    return m, 10.0 ** p


def _nearest(value: float, series: tuple[float, ...]) -> float:
    """The preferred value nearest to ``value`` (by ratio), over neighbouring decades."""
    m, scale = _decade(value)
    cands = [v * scale * f for v in series for f in (0.1, 1.0, 10.0)]
    return min(cands, key=lambda c: (abs(math.log(c / value)), c))


def fmt_value(value: float, unit: str) -> str:
    """A part value with an SI prefix: 6.34 kΩ, 68 nF, 1 µF."""
    for f, prefix in ((1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"), (1e-9, "n"), (1e-12, "p")):
        if value >= f * (1 - 1e-9):
            return f"{value / f:.3g} {prefix}{unit}"
    return f"{value:.3g} {unit}"


def resistor_fit(value: float) -> tuple[str, float]:
    """The nearest E96 resistor: (text, its value)."""
    r = float(f"{_nearest(value, E96):.3g}")
    return f"{fmt_value(r, 'Ω')} (E96)", r


def capacitor_fit(value: float) -> tuple[str, float]:
    """One E12 capacitor, or the E12 pair in parallel nearest to ``value`` when one is more than
    CAPACITOR_FIT off: (text, the value fitted)."""
    one = float(f"{_nearest(value, E12):.2g}")
    if abs(one / value - 1) <= CAPACITOR_FIT:
        return f"{fmt_value(one, 'F')} (E12)", one
    m, scale = _decade(value)
    base = [float(f"{v * scale * f:.2g}") for v in E12 for f in (0.01, 0.1, 1.0)]
    best = min(((a, b) for a in base for b in base if a >= b and a + b <= value * 1.05),
               key=lambda ab: (abs(math.log((ab[0] + ab[1]) / value)), -ab[0]), default=None)
    if best is None or abs(math.log((best[0] + best[1]) / value)) >= abs(math.log(one / value)):
        return f"{fmt_value(one, 'F')} (E12)", one
    a, b = best
    return f"{fmt_value(a, 'F')} + {fmt_value(b, 'F')} in parallel (E12)", float(f"{a + b:.4g}")


def parts_for(net: Netlist, machine: MachineProfile) -> list[Part]:
    """Every external part the netlist needs on this machine, in amplifier order.

    Parameters
    ----------
    net : Netlist
        The patch (its element values resolved as patchgen.patch.reading resolves them).
    machine : MachineProfile
        Its feedback resistor R_f and the external parts' tolerances.

    Returns
    -------
    list of Part
        Capacitors C1, C2, ... and resistors R1, R2, ..., numbered in order of use.
    """
    comp = machine.components
    reading = read(net, machine.imperfections.differentiator_rolloff_s)
    r_f = comp.feedback_resistor_ohm
    parts: list[Part] = []
    count = {"capacitor": 0, "resistor": 0}

    def add(kind: str, value: float, amp: str, jack: str | None, connection: str, purpose: str) -> Part:
        count[kind] += 1
        fit, fit_value = capacitor_fit(value) if kind == "capacitor" else resistor_fit(value)
        tol = comp.external_capacitor_tolerance if kind == "capacitor" else comp.external_resistor_tolerance
        part = Part(id=f"{kind[0].upper()}{count[kind]}", kind=kind, value=value,
                    unit="F" if kind == "capacitor" else "ohm", fit=fit, fit_value=fit_value, tolerance=tol,
                    amplifier=amp, jack=jack, connection=connection, purpose=purpose)
        parts.append(part)
        return part

    for amp in net.amplifiers:
        stage = reading.amplifiers[amp.id]
        if amp.role == "differentiator":
            for inp in amp.inputs:
                c = inp.weight * stage.T_d_s / r_f
                src = f"{inp.pot} wiper" if inp.pot else f"{inp.source} out" if inp.source in reading.amplifiers \
                    else f"sensor {inp.source}"
                cap = add("capacitor", c, amp.id, inp.jack, f"from {src} (in place of the {inp.jack} input "
                          f"resistor) to R{count['resistor'] + 1}",
                          f"differentiator input: T_d = R_f C / {inp.weight} = {stage.T_d_s:g} s")
                add("resistor", stage.rolloff_s / c, amp.id, inp.jack,
                    f"from {cap.id} to the {amp.id} summing junction",
                    f"series resistor: roll-off R C = {stage.rolloff_s:g} s")
        elif amp.role == "lag":
            add("capacitor", stage.tau_s / r_f, amp.id, None,
                f"across the {amp.id} feedback resistor (summing junction to output), {amp.id} patched as a summer",
                f"lag: tau = R_f C = {stage.tau_s:g} s")
    return parts
