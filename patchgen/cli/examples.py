"""`patchgen examples DIR`: copy the shipped designs, scenarios and profiles out for a user to edit."""

from __future__ import annotations

from pathlib import Path

import click

from patchgen.inputs.resources import EXAMPLES, example_files, shipped
from patchgen.render.outputs import json_text, write_files
from patchgen.render.terminal import print_listing, say

from . import cli
from .options import FORCE, json_option


@cli.command("examples")
@click.argument("out_dir", metavar="DIR", type=click.Path(file_okay=False))
@FORCE
@json_option("what was copied, by kind, and the files written")
def examples_cmd(out_dir: str, force: bool, as_json: bool) -> None:
    """Copy the shipped designs (DIR/designs), scenarios (DIR/sims) and machine and bench
    profiles (DIR/machines, DIR/benches) into DIR, to edit and run by path."""
    written = write_files(out_dir, example_files(), force=force, option="DIR")
    if as_json:
        click.echo(json_text({"copied": {sub: list(shipped(kind)) for kind, sub in EXAMPLES.items()},
                              "written": [str(p) for p in written]}), nl=False)
        return
    print_listing([(f"{sub}/", ", ".join(shipped(kind))) for kind, sub in EXAMPLES.items()])
    design = "bench-recommended" if "bench-recommended" in shipped("design") else shipped("design")[0]
    say(f"wrote {len(written)} files into {out_dir}; try:",
        f"  patchgen patch {Path(out_dir) / 'designs' / design}.toml -o {Path(out_dir) / 'patch'}")
