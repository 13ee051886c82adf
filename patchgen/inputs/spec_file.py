"""A design spec written back as TOML, for a spec patchgen chose (``recommended.toml``): the file
reads back, through patchgen.inputs.spec.load_spec, as the same spec.

tomli-w writes the TOML: a small, well-kept writer that quotes and escapes every string and float
as the TOML standard wants (a hand-written one would have to get ``inf``, exponents and escapes
right by itself). Fields left at None are left out (TOML has no null; None is every such field's
default). Profiles named by path are written as absolute paths, so the file may be read from
anywhere.
"""

from __future__ import annotations

import math
from pathlib import Path

import tomli_w

from patchgen.inputs.resources import resolve
from patchgen.inputs.spec import DesignSpec
from patchgen.plant.plant_model import DEFAULT


def spec_toml(spec: DesignSpec, header: str = "") -> str:
    """The spec as TOML text.

    Parameters
    ----------
    spec : DesignSpec
        A checked spec.
    header : str
        Comment lines to open the file with (each written after "# ").

    Returns
    -------
    str
        TOML that load_spec reads back as ``spec``.
    """
    data = spec.model_dump(mode="python", exclude_none=True)
    # left out as when read: the default plant model (every spec before the rotary pendulum's), and
    # a figure whose default is infinite (a rotary arm without a cable's limit), which TOML would
    # write as inf and a spec may not state
    plant = data["plant"]
    data["plant"] = {k: v for k, v in plant.items() if not (k == "model" and v == DEFAULT or v == math.inf)}
    for kind in ("machine", "bench"):
        where = resolve(kind, data[kind], spec.path, kind)
        if where == Path(data[kind]):  # a user's file, not a shipped profile's stem
            data[kind] = str(Path(data[kind]).resolve())
    lines = "".join(f"# {line}\n".replace("# \n", "#\n") for line in header.splitlines())
    return lines + tomli_w.dumps(data)
