"""patchgen check as one function: a filled static check read against the spec's patch, and the
single faults that explain the readings best."""

from __future__ import annotations

from dataclasses import dataclass

from patchgen.design.lqg import design_on
from patchgen.patch.fault_finding import Verdict, diagnose_readings
from patchgen.patch.netlist import Netlist
from patchgen.patch.readings import load_readings
from patchgen.patch.static_check import StaticCheck, static_check
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.scaling import scaled_patch


@dataclass(frozen=True)
class CheckReport:
    """The patch, its static check and the verdict on the readings."""

    netlist: Netlist
    check: StaticCheck
    verdict: Verdict

    def summary(self) -> dict:
        """The verdict and the faults ranked, as plain data (``--json``)."""
        v = self.verdict
        return {"design": self.netlist.design, "agree": v.agree, "readings": len(self.check.readings),
                "mismatched": list(v.mismatched),
                "ambiguous": sum(f.consistent for f in v.faults) > 1,  # more than one fault explains them all
                "faults": [{"kind": f.kind, "description": f.description, "chi_square": f.score,
                            "explained": f.explained, "of": f.of, "consistent": f.consistent} for f in v.faults]}


def run_check(inputs: Inputs, readings_path: str) -> CheckReport:
    """Patch the spec, read the filled static check at ``readings_path`` against it, and rank the
    single faults (a wrong pot, cord or sign) by how well each explains the readings."""
    spec, machine, bench = inputs
    net = scaled_patch(design_on(spec, machine, bench), machine, bench).netlist
    check = static_check(net, machine)
    measured = load_readings(readings_path, check, machine)
    return CheckReport(net, check, diagnose_readings(net, machine, check, measured))
