"""patchgen export's files: the configuration the LUCIDAC loads, a run script for its client
library, and a table of which element carries what with every coefficient beside its design value."""

from __future__ import annotations

from patchgen.pipeline.export import ExportReport
from patchgen.render.outputs import json_text

CONFIG = "lucidac-config.json"
SCRIPT = "run_lucidac.py"
TABLE = "lucidac-table.md"
EXPORT_FILES = (CONFIG, SCRIPT, TABLE)


def export_files(report: ExportReport) -> dict[str, str]:
    """File name -> text, the same bytes for the same spec."""
    return {CONFIG: json_text(report.config),
            SCRIPT: run_script(report), TABLE: table(report)}


def _jacks(report: ExportReport) -> list[str]:
    lp = report.lanes
    ref = lp.reference_V
    rows = [f"#   ACL_IN {acl}: {s}, {lp.sensor_volts_per_unit[s]:g} V per SI unit on the bench "
            f"({lp.sensor_volts_per_unit[s] / ref:g} machine units)" for s, acl in lp.sensor_acl.items()]
    rows.append(f"#   ACL_OUT {lp.output_acl}: u_c to the servo amplifier, 1 V per V of u_c "
                f"({1 / ref:g} machine units per V); the actuator gives {report.netlist.output.K_U_N_per_V:g} N/V")
    return rows


def run_script(report: ExportReport) -> str:
    """A short Python script that loads the configuration and runs it with lucipy's client."""
    run = report.plan.run_s
    default = "None" if run is None else repr(run)
    said = "until stopped (Ctrl-C)" if run is None else f"for {run:g} s ({report.plan.scenario})"
    return "\n".join([
        "#!/usr/bin/env python3",
        f'"""Load {report.netlist.design}\'s patch into a LUCIDAC and run it {said}.',
        "",
        f"Usage: python {SCRIPT} ENDPOINT [--seconds S]   (ENDPOINT e.g. tcp://192.168.1.100:5732)",
        'Needs lucipy (pip install "patchgen[lucidac]").',
        '"""',
        "",
        "# Front-panel jacks (machine unit = "
        f"{report.lanes.reference_V:g} V at the front panel, assumed: check the LUCIDAC manual):",
        *_jacks(report),
        "",
        "import argparse",
        "import json",
        "import pathlib",
        "",
        "from lucipy import LUCIDAC",
        "",
        "parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])",
        'parser.add_argument("endpoint", help="the LUCIDAC\'s endpoint, e.g. tcp://192.168.1.100:5732")',
        f'parser.add_argument("--seconds", type=float, default={default}, help="run time; none: until stopped")',
        "args = parser.parse_args()",
        f'config = json.loads(pathlib.Path(__file__).with_name("{CONFIG}").read_text())',
        "hc = LUCIDAC(args.endpoint)",
        "hc.set_circuit(config)",
        "if args.seconds is None:",
        "    hc.set_op_time(unlimited=True)",
        "else:",
        "    hc.set_op_time(sec=args.seconds)",
        "try:",
        "    hc.start_run()",
        "    if args.seconds is None:",
        '        input("Running: press Enter (or Ctrl-C) to stop.\\n")',
        "except KeyboardInterrupt:",
        "    pass",
        "finally:",
        "    hc.close()",
        "",
    ])


def table(report: ExportReport) -> str:
    """Which element carries what, and each lane's coefficient beside the netlist's gain it realises;
    per element input, the coefficient realised (the block's, ``out = sum c v``) and the design's."""
    lp, net = report.lanes, report.netlist
    out = [f"# {net.design} on the LUCIDAC", "", "| element | kind | carries | k0 (1/s) |", "|---|---|---|---:|"]
    out += [f"| {e.name} | {'integrator' if e.kind == 'int' else 'identity'} | {e.carries} | "
            f"{'' if e.k0_per_s is None else f'{e.k0_per_s:g}'} |" for e in lp.elements]
    out += ["", "| lane | from | to | coefficient | netlist gain |", "|---:|---|---|---:|---:|"]
    out += [f"| {i} | {ln.source} | {ln.target} | {ln.coeff:.6g} | {ln.gain:.6g} |" for i, ln in enumerate(lp.lanes)]
    out += ["", "Lanes in the order they are added; front-panel input or output n is lane 24 + n.", "",
            "| element | signal | realised | design |", "|---|---|---:|---:|"]
    for a in net.amplifiers:
        pots = {p.id: p for p in net.pots if p.amplifier == a.id}
        for src in dict.fromkeys(i.source for i in a.inputs):
            ins = [i for i in a.inputs if i.source == src]
            gain = sum((-1 if i.negated else 1) * i.weight * (pots[i.pot].setting if i.pot else 1.0) for i in ins)
            design = [pots[i.pot].coefficient for i in ins if i.pot] if len(ins) == 1 else []
            out.append(f"| {a.id} | {src} | {-gain:.6g} | {f'{design[0]:.6g}' if design else ''} |")
    out += ["", "(an integrator's coefficients are per its time scale 1/k0; design blank: the coefficient "
            "is exact, or split over inputs as a note says)", ""]
    out += [f"- {n}" for n in (*lp.notes, *net.notes)]
    if report.warnings:
        out += ["", "lucipy's sanity check says (identity elements 0-3 take the inputs of multipliers 0 and 1, "
                "which lucipy's check counts as multipliers in use):", *[f"- {w}" for w in report.warnings]]
    return "\n".join(out) + "\n"
