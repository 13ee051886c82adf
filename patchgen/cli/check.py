"""`patchgen check SPEC --readings FILE`: a filled static check against the patch, and the likeliest
fault when they differ."""

from __future__ import annotations

import sys

import click

from patchgen.design.lqg import design_on
from patchgen.inputs.errors import InputError
from patchgen.patch.build import build_patch
from patchgen.patch.fault_finding import diagnose_readings
from patchgen.patch.readings import load_readings
from patchgen.patch.static_check import static_check
from patchgen.render.check_view import print_verdict
from patchgen.render.outputs import json_text

from . import cli
from .inputs import load_inputs

DISAGREE_STATUS = 1  # the readings point at a fault


@cli.command("check")
@click.argument("spec")
@click.option("--readings", "readings_path", required=True, metavar="FILE",
              help="static-check.csv as patchgen patch wrote it, with the measured_V column filled in.")
@click.option("--json", "as_json", is_flag=True, help="Print the verdict and the faults as JSON.")
def check_cmd(spec: str, readings_path: str, as_json: bool) -> None:
    """Compare a filled static check with SPEC's patch and name the likeliest wrong pot, cord or sign.

    Exit 0 when every reading agrees with its expected value within its tolerance, 1 when not
    (with the single faults that explain the readings best, ranked), 2 for a bad readings file.
    """
    if not readings_path:
        raise InputError("--readings", "", "is an empty file name: give the filled static-check.csv")
    sp, machine, bench = load_inputs(spec)
    net = build_patch(design_on(sp, machine, bench), machine)
    check = static_check(net, machine)
    measured = load_readings(readings_path, check, machine)
    verdict = diagnose_readings(net, machine, check, measured)
    if as_json:
        click.echo(json_text({
            "design": net.design, "agree": verdict.agree, "mismatched": list(verdict.mismatched),
            "faults": [{"kind": f.kind, "description": f.description, "chi_square": f.score,
                        "explained": f.explained, "of": f.of, "consistent": f.consistent} for f in verdict.faults]}),
            nl=False)
    else:
        print_verdict(net, check, verdict)
    if not verdict.agree:
        sys.exit(DISAGREE_STATUS)
