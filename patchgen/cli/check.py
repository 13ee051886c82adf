"""`patchgen check SPEC --readings FILE`: a filled static check against the patch, and the likeliest
fault when they differ."""

from __future__ import annotations

import sys

import click

from patchgen.inputs.errors import InputError
from patchgen.pipeline.check import run_check
from patchgen.pipeline.inputs import load_inputs
from patchgen.render.check_view import print_verdict
from patchgen.render.outputs import json_text

from . import cli
from .options import MACHINE, json_option

DISAGREE_STATUS = 1  # the readings point at a fault


@cli.command("check")
@click.argument("spec")
@click.option("--readings", "readings_path", required=True, metavar="FILE",
              help="static-check.csv as patchgen patch wrote it, with the measured_V column filled in.")
@MACHINE
@json_option("the verdict and the faults")
def check_cmd(spec: str, readings_path: str, machine: str | None, as_json: bool) -> None:
    """Compare a filled static check with SPEC's patch and name the likeliest wrong pot, cord or sign.

    Exit 0 when every reading agrees with its expected value within its tolerance, 1 when not
    (with the single faults that explain the readings best, ranked), 2 for a bad readings file.
    """
    if not readings_path:
        raise InputError("--readings", "", "is an empty file name: give the filled static-check.csv")
    report = run_check(load_inputs(spec, machine=machine, command="check"), readings_path)
    if as_json:
        click.echo(json_text(report.summary()), nl=False)
    else:
        print_verdict(report.netlist, report.check, report.verdict)
    if not report.verdict.agree:
        sys.exit(DISAGREE_STATUS)
