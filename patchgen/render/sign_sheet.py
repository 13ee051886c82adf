"""The sheet's sign check in words (patchgen.patch.sign_check): a row per pot of what to set, what to
move and which way the reading must go."""

from __future__ import annotations

from patchgen.patch.netlist import Netlist
from patchgen.patch.sign_check import SignStep
from patchgen.plant.plant_model import CART, PlantModel
from patchgen.render.diagram_symbols import quantity_label


def sign_rows(steps: tuple[SignStep, ...], net: Netlist, ic_input: str = "IC jack",
              plant: PlantModel = CART) -> list[dict[str, str]]:
    """The sign check's rows: pot, the pots set, what to move, where to read, which way; an
    integrator's IC input named as the machine names it (``ic_input``), a hand-moved state as the
    plant's words say it."""
    sensors = {s.id: s for s in net.sensors}
    rows = []
    for st in steps:
        d = st.drive
        if d.kind == "hand":
            q = sensors[d.target].quantity
            move = plant.hand_words.get(q, f"move {quantity_label(q)}")
            move += " by hand" + (", read while it moves" if st.moving else "")
        elif d.kind == "input":
            move = f"{d.target} input at {_volts(d.volts)} ({d.source}), its sensor cord out"
        else:
            move = f"{d.target}'s {ic_input} at {_volts(d.volts)} ({d.source}): {d.target} at {_volts(-d.volts)}"
        read = f"u_c ({st.read})" if st.read == net.output.source else st.read
        if st.ramp:
            read += ", in OP"
            way = "rises" if st.expect > 0 else "falls"
            if d.kind == "ic" and d.target == st.read:  # its own feedback: back toward 0, or away
                way += " back to 0" if st.expect * -d.volts < 0 else " away from 0"
        else:
            way = ("+" if st.expect > 0 else "−") + (" while it moves" if st.moving else "")
        rows.append({"pot": st.pot, "on": ", ".join(st.on), "move": move, "read": read, "way": way})
    return rows


def sign_note(ic_input: str = "IC jack", plant: PlantModel = CART) -> str:
    """How the sign check is used, said once above its table."""
    return ("One row at a time, servo amplifier off, machine in IC: only the pots the row names at their settings, "
            f"every other pot at 0. {plant.sign_words} A test voltage comes from where the row says (a spare pot, "
            "set with its load connected), on the input named (its sensor cord unplugged) or on the "
            f"{ic_input} named (otherwise grounded). A reading in OP: switch to OP, see which way the integrator "
            "ramps, and back to IC at once. "
            "A reading that goes the other way has a sign wrong on its path (a cord on the wrong polarity, a sensor "
            "reversed).")


def _volts(v: float) -> str:
    return f"{'+' if v >= 0 else '−'}{abs(v):g} V"
