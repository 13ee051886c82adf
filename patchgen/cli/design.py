"""`patchgen design SPEC`: the LQG design report."""

from __future__ import annotations

import json

import click
from rich.console import Console

from patchgen.design.lqg import design
from patchgen.design.report import design_dict, print_design

from . import cli
from .inputs import load_inputs


def design_from_path(path: str):
    """Load the spec (and check the profiles it names) and run the design, taking the
    differentiator roll-off default from the machine."""
    spec, machine, _ = load_inputs(path)
    return design_of(spec, machine), machine


def design_of(spec, machine):
    """The design of a loaded spec, with the machine's differentiator roll-off as the default."""
    return design(spec, default_rolloff_s=machine.imperfections.differentiator_rolloff_s)


@cli.command("design")
@click.argument("spec")
@click.option("--json", "as_json", is_flag=True, help="Print the design as one JSON object.")
def design_cmd(spec: str, as_json: bool) -> None:
    """Compute the LQR gain, Kalman estimator, loop transfer recovery and loop margins of SPEC."""
    d, _ = design_from_path(spec)
    if as_json:
        click.echo(json.dumps(design_dict(d), indent=2, sort_keys=True, allow_nan=False))
    else:
        print_design(d, Console())
