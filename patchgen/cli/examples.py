"""`patchgen examples DIR`: copy the shipped designs, scenarios and profiles out for a user to edit."""

from __future__ import annotations

import click

from patchgen.inputs.resources import folder, shipped
from patchgen.render.outputs import write_files

from . import cli

# what is copied, and the sub-folder it goes to
COPIED = {"design": "designs", "scenario": "sims", "machine": "machines", "bench": "benches"}


def example_files() -> dict[str, bytes]:
    """Every shipped design, scenario and profile, keyed by its path under the examples folder."""
    files = {}
    for kind, sub in COPIED.items():
        for name in shipped(kind):
            files[f"{sub}/{name}.toml"] = folder(kind).joinpath(f"{name}.toml").read_bytes()
    return files


@cli.command("examples")
@click.argument("out_dir", metavar="DIR", type=click.Path(file_okay=False))
@click.option("--force", is_flag=True, help="Replace files that already exist.")
def examples_cmd(out_dir: str, force: bool) -> None:
    """Copy the shipped designs (DIR/designs), scenarios (DIR/sims) and machine and bench
    profiles (DIR/machines, DIR/benches) into DIR, to edit and run by path."""
    written = write_files(out_dir, example_files(), force=force, option="DIR")
    for kind, sub in COPIED.items():
        click.echo(f"{sub + '/':10} {', '.join(shipped(kind))}")
    click.echo(f"wrote {len(written)} files into {out_dir}; try: patchgen patch {out_dir}/designs/"
               f"{shipped('design')[0]}.toml -o out")
