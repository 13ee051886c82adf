"""patchgen identify and bench-test as functions: recordings of the standard tests made from
patchgen's own models, and a bench profile fitted to recordings."""

from __future__ import annotations

from dataclasses import dataclass

from patchgen.design.model import plant_params
from patchgen.identify.benchtest import bench_test_files
from patchgen.identify.identify import Identification, identify
from patchgen.identify.recording import expand
from patchgen.identify.rotary_benchtest import rotary_bench_test_files
from patchgen.pipeline.inputs import Inputs
from patchgen.plant.plant_model import ROTARY
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.measured_plant import as_on_bench


@dataclass(frozen=True)
class IdentifyReport:
    """The recordings read (folders expanded) and what the fits found."""

    files: tuple[str, ...]
    result: Identification


def run_identify(recordings: list[str], base: BenchProfile | None = None) -> IdentifyReport:
    """Read every recording (files, or folders of them) and fit the bench and plant to them;
    ``base`` gives what they do not (default: the bench they name, else uw-1991)."""
    files = expand(list(recordings))
    return IdentifyReport(tuple(files), identify(files, base))


@dataclass(frozen=True)
class BenchTestReport:
    """The recordings of every standard test (file name -> bytes), of which spec on which bench."""

    spec: str
    bench: str
    seed: int
    recordings: dict[str, bytes]

    def summary(self, written: list) -> dict:
        """What was recorded, as plain data (``--json``)."""
        return {"spec": self.spec, "bench": self.bench, "seed": self.seed, "written": [str(p) for p in written]}


def run_bench_test(inputs: Inputs, seed: int) -> BenchTestReport:
    """Record every standard bench test of the spec's plant on the bench (noise and random forces
    as the profile says; the same seed, the same bytes)."""
    spec, machine, bench = inputs
    plant, label = as_on_bench(plant_params(spec), bench), f"{spec.name} on bench {bench.id}"
    if spec.plant_model is ROTARY:
        files = rotary_bench_test_files(plant, bench, seed, label=label)
    else:
        files = bench_test_files(plant, bench, machine, seed, label=label)
    return BenchTestReport(spec.name, bench.id, seed, files)

