"""Plots drawn in the helper process come back as if drawn here; errors too."""

import os

import pytest

from patchgen.render import plot_helper


def where(x):
    return os.getpid(), x * 2


def fails(x):
    raise ValueError(f"bad {x}")


def test_without_a_helper_the_job_runs_here():
    assert plot_helper.submit(where, 21).result() == (os.getpid(), 42)


def test_a_started_helper_runs_one_job_and_returns_its_result():
    plot_helper.start()
    if plot_helper._helper is None:
        pytest.skip("no fork here, or threads running: plots are drawn in-process")
    pid, value = plot_helper.submit(where, 21).result()
    assert value == 42 and pid != os.getpid()
    assert plot_helper._helper is None  # one job per helper; the next runs here
    assert plot_helper.submit(where, 1).result() == (os.getpid(), 2)


def test_an_error_in_the_helper_is_raised_here():
    plot_helper.start()
    with pytest.raises(ValueError, match="bad 3"):
        plot_helper.submit(fails, 3).result()


def test_arguments_that_do_not_pickle_are_drawn_here():
    plot_helper.start()
    helper = plot_helper._helper
    assert plot_helper.submit(lambda f: (os.getpid(), f(2)), lambda x: x + 1).result() == (os.getpid(), 3)
    if helper is not None:  # the helper that got no job is gone, not left waiting for one
        helper[0].join(timeout=1)
        assert not helper[0].is_alive()


def test_a_helper_ends_when_the_command_closes_its_end(monkeypatch):
    """The fork copies the command's end of the pipe into the helper, which closes that copy: the
    command closing its end then ends the helper's wait for a job (before, the helper held the pipe
    open itself and waited on)."""
    monkeypatch.setattr(plot_helper, "_warm_up", lambda: None)  # the forked helper skips matplotlib
    plot_helper.start()
    if plot_helper._helper is None:
        pytest.skip("no fork here, or threads running: plots are drawn in-process")
    (proc, conn), plot_helper._helper = plot_helper._helper, None
    conn.close()
    proc.join(timeout=30)
    try:
        assert not proc.is_alive()
    finally:
        proc.terminate()
