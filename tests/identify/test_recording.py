"""Recordings and test figures read and checked: the header's units, the test line, the clock, and
one InputError naming the file and the column (or key) for everything wrong."""

import numpy as np
import pytest

from patchgen.identify.figures import read_figures
from patchgen.identify.recording import TESTS, parse_recording, read_recording, split_column
from patchgen.inputs.errors import InputError

STEP = "# test = actuator_step\n# cart held\nt_s, u_c_V, force_N\n" + "".join(
    f"{0.005 * k:.3f}, {1.0 if k >= 100 else 0.0}, {0.1 * k}\n" for k in range(300))


def error(text: str) -> InputError:
    with pytest.raises(InputError) as e:
        parse_recording(text, "rec.csv")
    assert e.value.source == "rec.csv" and "\n" not in e.value.line()
    return e.value


def test_a_recording_reads_with_its_notes_and_sample_interval():
    text = "# test = actuator_step\n# cart held\nt_s, u_c_V, force_N, theta_V\n" + "".join(
        f"{0.005 * k:.3f}, {1.0 if k >= 100 else 0.0}, {0.1 * k}, 0.5\n" for k in range(300))
    rec = parse_recording(text, "rec.csv")
    assert rec.test == "actuator_step" and rec.dt == pytest.approx(0.005) and rec.notes == {}
    assert set(rec.columns) == {"t_s", "u_c_V", "force_N"} and rec.ignored == ("theta_V",)
    assert rec.columns["force_N"][10] == pytest.approx(1.0)


def test_column_names_split_at_the_longest_quantity():
    assert split_column("s_dot_V") == ("s_dot", "V") and split_column("s_V") == ("s", "V")
    assert split_column("u_c_V") == ("u_c", "V") and split_column("volts") is None


@pytest.mark.parametrize("change, field, words", [
    (("force_N", "force_kN"), "force_kN", "unit 'kN'"),
    (("t_s", "t_ms"), "t_ms", "write t_s"),
    (("force_N", "pressure_Pa"), "pressure_Pa", "unknown column"),
    ((", force_N", ""), "force_N", "missing column"),
    (("# test = actuator_step", "# test = step"), "test", "unknown test"),
    (("# test = actuator_step\n", ""), "test", "first line names the test"),
    (("0.100, 0.0, 2.0", "0.100, 0.0, abc"), "force_N", "line 24: 'abc' is not a number"),
    (("0.100, 0.0, 2.0", "0.100, 0.0, nan"), "force_N", "not a finite number"),
    (("0.100, 0.0, 2.0", "0.100, 0.0"), "force_N", "line 24: missing: the line holds 2 of the 3 values"),
    (("0.100, 0.0, 2.0", "0.1015, 0.0, 2.0"), "t_s", "sample interval"),
])
def test_each_fault_is_one_line_naming_the_column(change, field, words):
    e = error(STEP.replace(*change, 1))
    assert e.field == field and words in e.message


def test_too_few_samples_names_the_test_and_its_minimum():
    e = error("# test = free_swing\nt_s, theta_V\n" + "".join(f"{0.01 * k}, 0.1\n" for k in range(40)))
    assert "too few samples: 40" in e.message and str(TESTS["free_swing"].min_samples) in e.message


def test_time_must_rise():
    e = error(STEP.replace("0.010, 0.0", "0.000, 0.0", 1))
    assert e.field == "t_s" and "does not rise" in e.message


def test_a_calibration_needs_both_columns_of_a_pair():
    e = error("# test = calibration\ns_m, theta_V\n0.1, 0.5\n0.2, 1.0\n0.3, 1.5\n")
    assert e.field in ("s_V", "theta_rad") and "missing column" in e.message


def test_a_quiet_recording_needs_a_sensor():
    e = error("# test = quiet\nt_s, u_c_V\n" + "".join(f"{k}, 0\n" for k in range(1000)))
    assert e.field == "s_V" and "at least one of s_V, theta_V, s_dot_V" in e.message


def test_unreadable_files_are_named(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_recording(tmp_path / "none.csv")
    with pytest.raises(InputError, match="is a directory, not a CSV recording"):
        read_recording(tmp_path)
    (tmp_path / "bin.csv").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputError, match="not UTF-8"):
        read_recording(tmp_path / "bin.csv")


def test_figures_are_checked_like_a_spec(tmp_path):
    p = tmp_path / "incline.toml"
    p.write_text('test = "incline"\nangle_deg = 9.5\ndistance_m = 1.325\ntime_s = -1.46\nmass_kg = 3.876\n')
    with pytest.raises(InputError) as e:
        read_figures(p)
    assert e.value.field == "time_s" and "greater than 0" in e.value.message
    p.write_text('test = "incline"\nangle_deg = 9.5\ndistance_m = 1.325\ntime_s = 1.46\nmass = 3.876\n')
    with pytest.raises(InputError) as e:
        read_figures(p)
    assert e.value.field in ("mass", "mass_kg")
    p.write_text('test = "masses"\nM_kg = 3.552\nm_kg = 0.324\n')
    m = read_figures(p)
    assert m.M_kg == 3.552 and m.g_m_per_s2 == 9.807 and m.d_m is None
    p.write_text('M_kg = 3.552\n')
    with pytest.raises(InputError, match="test = "):
        read_figures(p)


def test_numbers_are_read_as_written():
    rec = parse_recording("# test = integrator_drift\nt_s, out_V\n" + "".join(f"{k * 0.1:.1f}, {1e-3 * k:.6f}\n"
                                                                            for k in range(100)), "d.csv")
    assert np.allclose(np.diff(rec.columns["out_V"]), 1e-3)
