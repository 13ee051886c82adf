"""The plant is said once, in patchgen/plant/: no other module spells out its state names or a
list of its parameters (issue: the cart-pendulum's states were written in 7 places and its
parameter lists in 6, in 3 orders). The walk reads every module's literals: a tuple, list, set or
dict with three or more of the plant's state names, or of its parameter names, outside plant/ is
a second description. KNOWN counts, per module, the ones still to be moved, with where they
belong; it only shrinks."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import patchgen
from patchgen.inputs.spec import PlantSpec, RotaryPlantSpec
from patchgen.plant import rotary_pendulum
from patchgen.plant.cart_pendulum import PARAMETER_NAMES, PARAMETERS, STATE_NAMES, UNCERTAIN
from patchgen.plant.compiled import PLANT_VECTOR, VECTOR_PARAMETERS, plant_vector
from patchgen.plant.drive import MOTOR_PARAMETER_NAMES
from patchgen.plant.equations import PlantParams
from patchgen.plant.plant_model import CART, PLANT_MODELS, ROTARY
from patchgen.plant.rotary_equations import RotaryParams

PKG = Path(patchgen.__file__).parent
KNOWN: dict[str, tuple[int, str]] = {}  # module -> (how many, where they belong): none left


def _lists_of_names() -> list[tuple[str, int, str]]:
    """(module, line, which) for every literal naming three or more states or parameters."""
    found = []
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG).as_posix()
        if rel.startswith("plant/"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            items = (node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set))
                     else node.keys if isinstance(node, ast.Dict) else None)
            if items is None:
                continue
            words = {x.value for x in items if isinstance(x, ast.Constant) and isinstance(x.value, str)}
            for which, names in (("states", STATE_NAMES), ("parameters", PARAMETER_NAMES),
                                 ("motor", MOTOR_PARAMETER_NAMES), ("states", rotary_pendulum.STATE_NAMES),
                                 ("parameters", rotary_pendulum.PARAMETER_NAMES)):
                if len(words & set(names)) >= 3:
                    found.append((rel, node.lineno, which))
    return found


def test_no_module_outside_plant_lists_the_plant_s_states_or_parameters():
    per: dict[str, list[tuple[int, str]]] = {}
    for module, line, which in _lists_of_names():
        per.setdefault(module, []).append((line, which))
    extra = {m: found for m, found in per.items() if len(found) > KNOWN.get(m, (0, ""))[0]}
    assert extra == {}, "a second description of the plant: ask patchgen.plant.cart_pendulum instead"
    gone = {m for m in KNOWN if len(per.get(m, [])) < KNOWN[m][0]}
    assert gone == set(), "moved: lower KNOWN's count for these"


def test_the_walk_finds_a_list_written_out_again(tmp_path, monkeypatch):
    """The walk is not blind: a module that spells the states out is found."""
    probe = PKG / "design" / "_probe_states.py"
    probe.write_text('ORDER = ("s", "theta", "s_dot", "theta_dot")\nP = ["M", "m", "b_VF"]\n'
                     'D = {"R_m", "K_t", "K_g"}\n')
    try:
        found = [f for f in _lists_of_names() if f[0] == "design/_probe_states.py"]
    finally:
        probe.unlink()
    assert found == [("design/_probe_states.py", 1, "states"), ("design/_probe_states.py", 2, "parameters"),
                     ("design/_probe_states.py", 3, "motor")]


@pytest.mark.parametrize("table, plant, params", [(PlantSpec, CART, PlantParams),
                                                   (RotaryPlantSpec, ROTARY, RotaryParams)])
def test_the_spec_s_plant_table_is_the_plant_model_s_parameters(table, plant, params):
    schema = table.model_json_schema()
    assert tuple(schema["properties"]) == ("model",) + plant.parameter_names
    assert schema["properties"]["model"]["const"] == plant.name and set(PLANT_MODELS) == {"cart-pendulum",
                                                                                         "rotary-pendulum"}
    for p in plant.parameters:
        field = schema["properties"][p.name]
        if "anyOf" in field:  # a figure that may be left out: its bounds on the number
            bounds = next(a for a in field["anyOf"] if a["type"] == "number")
            lo, hi = bounds["ge"], bounds["le"]
        else:  # an infinite bound is left out of the schema
            lo, hi = field["minimum"], field.get("maximum", float("inf"))
        assert (lo, hi, field.get("default")) == (p.lo, p.hi, p.default)
        assert field["description"] == p.what
    assert set(schema["required"]) == {p.name for p in plant.parameters
                                       if p.default is None and p.name not in plant.optional}
    assert tuple(params.__dataclass_fields__) == plant.parameter_names
    assert plant.parameters == (PARAMETERS if plant is CART else rotary_pendulum.PARAMETERS)


@pytest.mark.parametrize("seed", range(3))
def test_the_compiled_vector_is_the_plant_s(seed):
    import numpy as np
    rng = np.random.default_rng(seed)
    plant = PlantParams(**{p.name: float(rng.uniform(max(p.lo, 0.1), min(p.hi, 10.0))) for p in PARAMETERS})
    v = plant_vector(plant)
    assert len(v) == len(PLANT_VECTOR) == len(VECTOR_PARAMETERS)
    for i, name in enumerate(VECTOR_PARAMETERS):
        want = plant.d / 2 if PLANT_VECTOR[i] == "half_track" else getattr(plant, name)
        assert v[i] == want
    assert set(UNCERTAIN) == {"M", "m", "l", "b_VF", "c"}  # gravity and the track are not a bench's unknowns
