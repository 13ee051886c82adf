"""Every file identify writes, as name -> bytes for the all-or-nothing writer
(patchgen.render.outputs.write_files): bench.toml, plant.toml, report.md, report.json and a fit
plot per recording; and identify on the terminal."""

from __future__ import annotations

from rich.console import Console
from rich.markup import escape

from patchgen.identify.identify import Identification
from patchgen.identify.profile import bench_toml, plant_toml
from patchgen.identify.rotary_profile import rotary_bench_toml, rotary_plant_toml
from patchgen.plant.plant_model import ROTARY
from patchgen.profiles.bench import BenchProfile
from patchgen.render.identify_plots import fit_plot, plot_name
from patchgen.render.identify_report import report_json, report_markdown
from patchgen.render.terminal import add_row, number, show, table, text

FIXED = ("bench.toml", "plant.toml", "report.md", "report.json")


def identify_files(result: Identification, files: list[str], base: BenchProfile, bench_id: str,
                   name: str) -> dict[str, bytes]:
    """The identified bench and plant, the report and the plots.

    Parameters
    ----------
    result : Identification
        What identify found.
    files : list of str
        The files read (named in the outputs).
    base : BenchProfile
        The base profile (what was not identified).
    bench_id, name : str
        The new bench profile's id and name.

    Returns
    -------
    dict
        File name -> bytes.
    """
    out: dict[str, bytes] = {}
    plots: dict[str, str] = {}
    taken: set[str] = set(FIXED)
    for f in result.fits:
        name_png = plot_name(f.source, taken)
        drawn = fit_plot(f, name_png.removesuffix(".png"))
        if drawn:
            plots[f.source] = name_png
            out.update(drawn)
    if base.plant == ROTARY.name:
        out["bench.toml"] = rotary_bench_toml(result, base, bench_id, name, files).encode()
        out["plant.toml"] = rotary_plant_toml(result, files).encode()
    else:
        out["bench.toml"] = bench_toml(result, base, bench_id, name, files).encode()
        out["plant.toml"] = plant_toml(result, files).encode()
    out["report.md"] = report_markdown(result, files, plots).encode()
    out["report.json"] = report_json(result, files, plots).encode()
    return out


def print_identification(result: Identification, written: list, out_dir: str,
                         console: Console | None = None) -> None:
    """The warnings on stderr, then each identified figure with its 95 % interval (or where it came
    from), and the files written."""
    console = console or Console()
    warn = Console(stderr=True)
    for w in result.warnings:
        warn.print(f"warning: {escape(w)}", highlight=False)
    t = table("Identified (95 % intervals; what was not identified, from where it came)", text("parameter"),
              number("value"), text("unit"), text("95 % interval or from"))
    for key, p in list(result.bench.items()) + list(result.plant.items()):
        e = p.estimate
        shown = p.value if isinstance(p.value, str) else f"{p.value:.5g}"
        add_row(t, key, shown, p.unit, f"{e.low:.4g} to {e.high:.4g}" if e else escape(p.origin))
    show(console, t)
    console.print(f"wrote {len(written)} files into {escape(str(out_dir))}", highlight=False)
