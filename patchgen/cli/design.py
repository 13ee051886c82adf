"""`patchgen design SPEC`: the LQG design report."""

from __future__ import annotations

import click

from patchgen.pipeline.design import run_design
from patchgen.pipeline.inputs import load_inputs
from patchgen.render.design_tables import print_design
from patchgen.render.outputs import json_text

from . import cli
from .options import MACHINE, json_option


@cli.command("design")
@click.argument("spec")
@MACHINE
@json_option("the design as one object")
def design_cmd(spec: str, machine: str | None, as_json: bool) -> None:
    """Compute the LQR gain, Kalman estimator, loop transfer recovery and loop margins of SPEC."""
    report = run_design(load_inputs(spec, machine=machine, command="design"))
    if as_json:
        click.echo(json_text(report.summary()), nl=False)
    else:
        print_design(report.design)
