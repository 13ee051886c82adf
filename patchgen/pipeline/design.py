"""patchgen design as one function: the spec's LQG design on the machine and bench it names."""

from __future__ import annotations

from dataclasses import dataclass

from patchgen.design.lqg import Design, design_on
from patchgen.design.report import design_dict
from patchgen.pipeline.inputs import Inputs


@dataclass(frozen=True)
class DesignReport:
    """The design: LQR gain, estimator, loop transfer recovery, poles, zeros and margins."""

    design: Design

    def summary(self) -> dict:
        """Every figure the design report prints, as plain JSON-able data (``--json``)."""
        return design_dict(self.design)


def run_design(inputs: Inputs) -> DesignReport:
    """Design the spec on its machine and bench (a dc_motor's drive and the bench's noise as the
    spec asks): patchgen.design.lqg.design_on."""
    return DesignReport(design_on(*inputs))
