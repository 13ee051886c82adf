"""Candidates that were not run, summarised for a terminal: one line per kind of refusal with its
count ("4 candidates do not fit: the patch needs more pots than the Comdyna GP-6 x2 has (16)")
where the comparison's files and --json keep each one's full reason."""

from __future__ import annotations

import re

# the allocator's words when a patch needs more of the machine than it has (patchgen.patch.allocation)
_SHORT = re.compile(r"the patch needs (?:at least )?(\d+) amplifiers \((\d+) integrators\) and (\d+) pots; "
                    r"(.+?) has (\d+) amplifiers \((\d+) integrators\) and (\d+) pots")
_NUMBER = re.compile(r"\d+(?:\.\d+)?")


def kind(error: str) -> str:
    """What kind of refusal ``error`` is: what the machine lacks, when it says; otherwise the
    message with its numbers masked (two messages differing only in figures are one kind)."""
    m = _SHORT.search(error)
    if m is not None:
        need_amp, need_int, need_pot, machine, have_amp, have_int, have_pot = m.groups()
        short = [(what, have) for what, need, have in (("amplifiers", need_amp, have_amp),
                                                        ("integrators", need_int, have_int),
                                                        ("pots", need_pot, have_pot)) if int(need) > int(have)]
        if short:
            what = [w for w, _ in short]
            what = ", ".join(what[:-1]) + " and " + what[-1] if len(what) > 1 else what[0]
            return f"do not fit: the patch needs more {what} than {machine} has ({', '.join(h for _, h in short)})"
    return _NUMBER.sub("#", error)


def summary(refused: list[tuple[str, str]]) -> list[str]:
    """One line per kind of refusal among ``refused`` (label, error), the commonest first: how many,
    and what the machine lacks or, for another kind, one candidate's label and reason."""
    groups: dict[str, list[tuple[str, str]]] = {}
    for label, error in refused:
        groups.setdefault(kind(error), []).append((label, error))
    lines = []
    for k, members in sorted(groups.items(), key=lambda g: -len(g[1])):
        n = len(members)
        many = f"{n} candidate{'s' * (n > 1)}"
        if k.startswith("do not fit"):
            lines.append(f"{many} {k if n > 1 else k.replace('do not', 'does not', 1)}")
            continue
        label, error = members[0]
        others = f"; {n - 1} more like it" if n > 1 else ""
        lines.append(f"{many} not run ({label}{others}): {error}")
    return lines
