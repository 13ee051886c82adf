"""What identify says: a Markdown report (report.md) and the same as JSON (report.json): the bench
profile's and the plant's values with their intervals and origins, each recording's estimates,
checks and notes, and the warnings."""

from __future__ import annotations

import math

from patchgen.identify.estimate import Estimate
from patchgen.identify.identify import Identification, Parameter
from patchgen.render.outputs import json_text

TITLE = "Bench identification"


def _num(x: float) -> str:
    return f"{x:.4g}" if math.isfinite(x) else str(x)


def _interval(e: Estimate | None) -> str:
    return "" if e is None else f"{_num(e.low)} to {_num(e.high)}"


def _row(name: str, p: Parameter) -> str:
    value = p.value if isinstance(p.value, str) else _num(p.value)
    method = p.estimate.method if p.estimate else ""
    return f"| {name} | {value} | {p.unit} | {_interval(p.estimate)} | {p.origin} | {method} |"


def report_markdown(result: Identification, files: list[str], plots: dict[str, str]) -> str:
    """The report as Markdown.

    Parameters
    ----------
    result : Identification
        What identify found.
    files : list of str
        The files read.
    plots : dict
        Recording -> its fit plot's file name.

    Returns
    -------
    str
        The report.
    """
    out = [f"# {TITLE}", "", f"From {len(files)} files: " + ", ".join(f"`{f}`" for f in files) + ".",
           "Intervals are 95 %; each says how it was found. Values not identified come from the base profile "
           f"`{result.base}` and are named so.", ""]
    if result.warnings:
        out += ["## Warnings", ""] + [f"- {w}" for w in result.warnings] + [""]
    head = ["| parameter | value | unit | 95 % interval | from | method |", "|---|---|---|---|---|---|"]
    out += ["## Bench profile (bench.toml)", ""] + head + [_row(k, p) for k, p in result.bench.items()] + [""]
    out += ["## Plant (plant.toml)", ""] + head + [_row(k, p) for k, p in result.plant.items()] + [""]
    if result.extra:
        out += ["## Also found", "", "| quantity | value | unit | 95 % interval | from |", "|---|---|---|---|---|"]
        out += [f"| {k} | {_num(e.value)} | {e.unit} | {_interval(e)} | {e.source} |" for k, e in result.extra.items()]
        out.append("")
    if result.checks:
        out += ["## Recordings of one test against each other", ""]
        out += [f"- {'**rejected**' if c.rejected else 'ok'}: {c.text}" for c in result.checks] + [""]
    out += ["## Recordings", ""]
    for f in result.fits:
        out += [f"### `{f.source}`: {f.title or f.test}", ""]
        if f.estimates:
            out += ["| estimate | value | unit | 95 % interval | method |", "|---|---|---|---|---|"]
            out += [f"| {k} | {_num(e.value)} | {e.unit} | {_interval(e)} | {e.method} |"
                    for k, e in f.estimates.items()]
            out.append("")
        for c in f.checks:
            out.append(f"- {'**the data reject the model**' if c.rejected else 'model holds'} ({c.name}): {c.text}")
        out += [f"- {n}" for n in f.notes]
        if f.source in plots:
            out += ["", f"![fit of {f.source}]({plots[f.source]})"]
        out.append("")
    return "\n".join(out)


def report_json(result: Identification, files: list[str], plots: dict[str, str]) -> str:
    """The report as JSON (sorted keys): bench, plant, extra, checks, warnings, recordings."""
    data = {"files": files, "base_profile": result.base, "warnings": result.warnings,
            "bench": {k: p.to_dict() for k, p in result.bench.items()},
            "plant": {k: p.to_dict() for k, p in result.plant.items()},
            "extra": {k: e.to_dict() for k, e in result.extra.items()},
            "checks": [c.to_dict() for c in result.checks],
            "recordings": [dict(f.to_dict(), plot=plots.get(f.source)) for f in result.fits]}
    return json_text(_plain(data))


def _plain(x):
    """numpy scalars and bools as Python's, so that json writes them."""
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if hasattr(x, "item"):
        return x.item()
    return x
