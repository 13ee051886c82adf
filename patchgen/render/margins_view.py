"""The sheet's margins: the design's beside the patch's (patchgen.patch.as_patched), as the words
and figures the design summary shows, the banner of a patch that loses the design's phase margin,
and margins.json."""

from __future__ import annotations

from patchgen.design.margins import Margins
from patchgen.patch import compensator_fit
from patchgen.patch.as_patched import FIXED_TOL, AsPatched, LoopFigures
from patchgen.patch.law_error import LawError
from patchgen.render.outputs import json_text

MARGINS_SCHEMA = "patchgen.margins/1"
NEGLIGIBLE = 1e-4  # a relative error below this prints as "< 0.01 %" (its digits are the arithmetic's)


def margin_cells(m: Margins) -> dict[str, str]:
    """A loop's margins as the sheet prints them: gain limits as factors and dB, phase and delay margins."""
    if not m.stable:
        return {"stable": "no"}
    return {"lower GM": "none" if m.lower_gm is None else f"{m.lower_gm:.4f} ({m.lower_gm_db:+.2f} dB)",
            "upper GM": "inf" if m.upper_gm is None else f"{m.upper_gm:.4f} ({m.upper_gm_db:+.2f} dB)",
            "PM": "-" if m.pm_deg is None else f"{m.pm_deg:.2f} deg",
            "delay margin": "-" if m.delay_margin_s is None else f"{m.delay_margin_s * 1000:.1f} ms"}


def patched_context(j: AsPatched) -> dict:
    """The sheet's 'Margins as patched': a row per loop (as designed, as patched on the design model
    and on the bench: its margins and closed-loop poles), the wired law's error against the design's
    and the error each cause adds (its largest over the loop's band)."""
    lo, hi = j.law.band
    law = (", ".join(f"{percent(e)} at {w:g}" for w, e in j.law.at) + f" rad/s; largest {_largest(j.law)} over the "
           f"loop's band, {lo:.3g} to {hi:.3g} rad/s")
    return {"loops": [{"loop": lp.loop, "law": lp.law, "margins": loop_cells(lp, j),
                       "poles": ", ".join(pole_text(p) for p in _sorted(lp))} for lp in j.loops],
            "law": law, "causes": "; ".join(f"{c.what}: {_largest(c.error)}" for c in j.causes)}


def loop_cells(lp: LoopFigures, j: AsPatched) -> str:
    """One loop's margins in words: the figures, or its rightmost pole when it is not stable; a
    fixed pole at the origin named beside them; for the patch on the design model, the share of
    the design's phase margin it keeps."""
    cells = margin_cells(lp.margins) if lp.margins.stable else {"not stable, rightmost pole": pole_text(lp.rightmost)}
    if lp.fixed:
        n = len(lp.fixed)
        cells["and"] = f"{'a pole' if n == 1 else f'{n} poles'} at 0 that no loop gain moves (marginal)"
    if lp is j.patched and j.pm_share is not None:
        cells["kept"] = f"{percent(j.pm_share)} of the design's PM"
    return "; ".join(f"{k} {v}" for k, v in cells.items())


def patched_banner(j: AsPatched) -> str:
    """One line for the top of the sheet when the patched loop keeps less than
    compensator_fit.KEEP_PM_SHARE of the design's phase margin ("" when it keeps it)."""
    if j.keeps_margin:
        return ""
    keep = f"{100 * compensator_fit.KEEP_PM_SHARE:.0f} %"
    m, d = j.patched.margins, j.designed.margins
    kept = (f"keeps {percent(j.pm_share)} of the design's phase margin ({m.pm_deg:.1f} of {d.pm_deg:.1f} deg)"
            if m.stable and m.pm_deg is not None else "is not stable")
    why = ("no realisation tried that fits the machine keeps " + keep if j.realization == "compensator"
           else "wired as its states, the patch has no other realisation to choose")
    return f"As patched, the loop on the design model {kept}: {why}. See 'Margins as patched'."


def margins_json(j: AsPatched, design: str) -> str:
    """margins.json: the loops as designed and as patched, the wired law's error and its causes."""
    return json_text({"schema": MARGINS_SCHEMA, "design": design, **j.as_dict()})


def percent(x: float) -> str:
    """A share or relative error as a percentage, two significant digits; a negligible one as such."""
    if abs(x) < NEGLIGIBLE:
        return "< 0.01 %"
    return f"{100 * x:.0f} %" if abs(x) >= 0.1 else f"{100 * x:.2g} %"


def pole_text(z: complex) -> str:
    """A pole as the sheet prints it (four significant digits, typographic minus; 0 for one at the
    origin to within FIXED_TOL)."""
    if abs(z) <= FIXED_TOL:
        return "0"
    text = f"{z.real:+.4g}" if z.real > 0 else f"{z.real:.4g}"
    text += f" ± {abs(z.imag):.4g}j" if abs(z.imag) > 1e-12 * abs(z) else ""
    return text.replace("-", "−")


def _largest(e: LawError) -> str:
    """The largest error and where (a negligible one without its frequency: the arithmetic's)."""
    return percent(e.peak[1]) + ("" if e.peak[1] < NEGLIGIBLE else f" at {e.peak[0]:.3g} rad/s")


def _sorted(lp: LoopFigures) -> list[complex]:
    """The poles slowest first, each complex pair once (Im > 0)."""
    return sorted((complex(p) for p in lp.poles if p.imag >= 0), key=lambda p: (-p.real, p.imag))
