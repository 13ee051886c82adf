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
    assert plot_helper.submit(lambda f: (os.getpid(), f(2)), lambda x: x + 1).result() == (os.getpid(), 3)
