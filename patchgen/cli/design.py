"""`patchgen design SPEC`: the LQG design report."""

from __future__ import annotations

import json

import click
from rich.console import Console

from ..design import design
from ..machine import load_machine
from ..report import design_dict, print_design
from ..spec import load_spec
from . import cli


def design_from_path(path: str):
    """Load the spec and run the design, taking the differentiator roll-off default from the machine."""
    spec = load_spec(path)
    machine = load_machine(spec.machine, spec.path)
    return design(spec, default_rolloff_s=machine.imperfections.differentiator_rolloff_s), machine


@cli.command("design")
@click.argument("spec", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print the design as one JSON object.")
def design_cmd(spec: str, as_json: bool) -> None:
    """Compute the LQR gain, Kalman estimator, loop transfer recovery and loop margins of SPEC."""
    d, _ = design_from_path(spec)
    if as_json:
        click.echo(json.dumps(design_dict(d), indent=2, sort_keys=True))
    else:
        print_design(d, Console())
