"""patchgen: from an optimal cart-pendulum controller to a checked Comdyna GP-6 patch.

The Python API (docs/api.md) is loaded on first use, so ``import patchgen`` stays cheap:

- :func:`load_design` a shipped design by name, a spec file or a spec, designed;
- :func:`plant_ss`, :func:`compensator_ss`, :func:`loop_ss`, :func:`closed_loop_ss` that design
  as ``control.StateSpace`` objects with named signals;
- :func:`design_on` the design stage on a loaded spec and profiles (no file read); the stage
  itself is :func:`patchgen.design.lqg.design` (``patchgen.design`` is the design folder);
- :func:`loop_margins` exact gain, phase and delay margins of a loop (A, B, C, D), found without
  a frequency grid.
"""

import os as _os

__version__ = "0.2.0"

# numba's compiled kernels go to a per-user cache, not beside the installed sources: files pip did
# not install outlive `pip uninstall` and leave site-packages/patchgen a namespace package that
# shadows a later (editable) install. Set before numba is first imported; a user's setting wins.
_os.environ.setdefault("NUMBA_CACHE_DIR", _os.path.join(
    _os.environ.get("XDG_CACHE_HOME") or _os.path.join(_os.path.expanduser("~"), ".cache"), "patchgen", "numba"))

# patchgen's matrices are a few dozen wide at most: a BLAS thread pool never pays for itself on
# them, and on a busy machine its waiting threads slow every small call (scipy's L-BFGS-B on four
# parameters: 2.8 ms alone, 57 ms with a second process running). One thread, unless the user
# says otherwise; it takes effect when patchgen is imported before numpy, as the command is.
for _var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

_LAZY = {
    "load_design": "patchgen.design.lti",
    "plant_ss": "patchgen.design.lti",
    "compensator_ss": "patchgen.design.lti",
    "loop_ss": "patchgen.design.lti",
    "closed_loop_ss": "patchgen.design.lti",
    "load_spec": "patchgen.inputs.spec",
    "loop_margins": "patchgen.design.margins",
    "design_on": "patchgen.design.lqg",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str):
    """Import a public name's module when the name is first used."""
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'patchgen' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
