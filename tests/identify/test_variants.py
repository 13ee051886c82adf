"""Valid ways of writing a recording read the same as bench-test's own: CRLF or CR line ends, a
byte-order mark, a '+' sign, blank and comment lines among the samples; a coarse converter's
levels and a cart at rest after its coast are not clipping; identify gives the same answer."""

import numpy as np
import pytest

from patchgen.identify.cells import flat_top, plain_number
from patchgen.identify.identify import identify
from patchgen.identify.recording import parse_recording
from patchgen.profiles.bench import load_bench
from tests.inputs.badinput_recordings import _with_column, good_files


def _same(a, b):
    assert a.test == b.test and a.columns.keys() == b.columns.keys()
    for k in a.columns:
        assert np.array_equal(a.columns[k], b.columns[k]), k


def _plus(text: str) -> str:
    lines = text.splitlines()
    lines[10] = ", ".join(c.strip() if c.strip().startswith("-") else "+" + c.strip() for c in lines[10].split(","))
    return "\n".join(lines) + "\n"


VARIANTS = {
    "crlf": lambda s: s.replace("\n", "\r\n"),
    "cr": lambda s: s.replace("\n", "\r"),
    "bom-crlf": lambda s: "\ufeff" + s.replace("\n", "\r\n"),
    "plus-sign": _plus,
    "blank-and-comment-lines": lambda s: s.replace("\n", "\n\n# a note among the samples\n   \n", 40).replace(
        "\n\n# a note among the samples\n   \n", "\n", 39),
    "spaces-around-test": lambda s: s.replace("# test = ", "#   test   =   ", 1),
}


@pytest.mark.parametrize("name", list(VARIANTS))
@pytest.mark.parametrize("file", ["actuator-step.csv", "quiet.csv", "calibration.csv"])
def test_a_valid_variant_reads_the_same(name, file):
    text = good_files()[file]
    _same(parse_recording(VARIANTS[name](text), "a.csv"), parse_recording(text, "a.csv"))


def test_identify_gives_the_same_answer_for_crlf_with_a_bom(tmp_path):
    text = good_files()["actuator-step.csv"]
    (tmp_path / "plain.csv").write_text(text)
    (tmp_path / "windows.csv").write_bytes(("\ufeff" + text.replace("\n", "\r\n")).encode())
    base = load_bench("uw-1991")
    a = identify([str(tmp_path / "plain.csv")], base).bench
    b = identify([str(tmp_path / "windows.csv")], base).bench
    assert {k: p.value for k, p in a.items()} == {k: p.value for k, p in b.items()}


@pytest.mark.parametrize("cell, value", [("0.5", 0.5), (" -3e-2 ", -0.03), ("+.5", 0.5), ("7.", 7.0), ("1E3", 1e3),
                                         ("1_0", None), ("0x10", None), ("nan", None), ("inf", None), ("\uff11", None),
                                         ("1\u00a0", None), ("", None), ("1.2.3", None), ("e5", None)])
def test_plain_decimal_notation_only(cell, value):
    assert plain_number(cell) == value


def test_a_coarse_converter_is_not_clipping():
    rng = np.random.default_rng(3)
    noise = np.round(rng.standard_normal(4000) * 0.002 / 0.005) * 0.005  # a 5 mV converter under 2 mV of noise
    assert flat_top(noise) is None
    swing = np.round(np.sin(np.arange(4000) * 0.01) / 0.005) * 0.005  # a slow swing read coarsely
    assert flat_top(swing) is None
    held = np.clip(np.sin(np.arange(4000) * 0.01) + 0.001 * rng.standard_normal(4000), -0.5, 0.5)
    assert flat_top(held) is not None


def _at_rest(t, x):
    q = np.round(x / 0.005) * 0.005
    q[-300:] = q.max() if abs(q[-1] - q.max()) < abs(q[-1] - q.min()) else q.min()
    return q


def test_a_coast_read_coarsely_that_comes_to_rest_is_accepted():
    text = _with_column(good_files()["coast-down-1.csv"], "s_V", _at_rest)
    s = parse_recording(text, "coast.csv").columns["s_V"]
    assert s[-1] == s[-300] and s[-1] in (s.max(), s.min())  # at rest, on one level, at its extreme
