"""`patchgen design SPEC`: the LQG design report."""

from __future__ import annotations

import click

from patchgen.design.lqg import Design, design_on
from patchgen.design.report import design_dict
from patchgen.profiles.machine import MachineProfile
from patchgen.render.design_tables import print_design
from patchgen.render.outputs import json_text

from . import cli
from .inputs import load_inputs


def design_from_path(path: str) -> tuple[Design, MachineProfile]:
    """The design of a spec file or shipped name on the machine and bench it names (each loaded
    and checked first), and that machine."""
    spec, machine, bench = load_inputs(path)
    return design_on(spec, machine, bench), machine


@cli.command("design")
@click.argument("spec")
@click.option("--json", "as_json", is_flag=True, help="Print the design as one JSON object.")
def design_cmd(spec: str, as_json: bool) -> None:
    """Compute the LQR gain, Kalman estimator, loop transfer recovery and loop margins of SPEC."""
    d, _ = design_from_path(spec)
    if as_json:
        click.echo(json_text(design_dict(d)), nl=False)
    else:
        print_design(d)
