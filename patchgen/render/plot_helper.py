"""Plots drawn on the other core: a helper process loads matplotlib while the command computes.

Loading matplotlib and drawing a first figure (fonts, tick machinery) takes about 0.5 s of a
simulate that otherwise needs about a second. A command that will plot calls :func:`start` first:
where processes fork (Linux), a helper process starts, imports matplotlib and draws a scrap
figure, on the second core while this one designs and simulates. :func:`submit` then hands it
the plotting function (a module-level function, passed by name) and its arguments, and
``result()`` waits for what it returns. Without a helper (no fork, one core, or never started)
the function simply runs here, so the files are the same either way. One job per helper.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
from collections.abc import Callable

_helper = None  # (process, connection) of the started helper, until a job takes it


def start() -> None:
    """Start the helper, when processes fork and a second core is there to run it."""
    global _helper
    if _helper is not None or (os.cpu_count() or 1) < 2 or threading.active_count() > 1:
        return
    if "fork" not in multiprocessing.get_all_start_methods():
        return
    ctx = multiprocessing.get_context("fork")
    mine, theirs = ctx.Pipe()
    proc = ctx.Process(target=_serve, args=(theirs, mine), daemon=True, name="patchgen-plots")
    proc.start()
    theirs.close()
    _helper = (proc, mine)


class Job:
    """A plot being drawn; ``result()`` returns what the plotting function returned."""

    def __init__(self, fn: Callable, args: tuple):
        self._fn, self._args, self._conn, self._proc = fn, args, None, None
        global _helper
        if _helper is not None:
            (self._proc, self._conn), _helper = _helper, None
            try:
                self._conn.send((fn, args))
            except Exception:  # arguments that do not pickle, or the helper gone: draw here
                self._close(stop=True)  # it has no job and holds nothing of ours: no wait for its warm-up

    def result(self):
        if self._conn is not None:
            try:
                ok, value = self._conn.recv()
            except (OSError, EOFError):  # the helper died: draw here
                ok, value = None, None
            except BaseException:  # Ctrl-C: stop the helper too
                self._close(stop=True)
                raise
            self._close()
            if ok:
                return value
            if ok is False:
                raise value
        return self._fn(*self._args)

    def _close(self, stop: bool = False) -> None:
        self._conn.close()  # the helper's next recv ends, and so does the helper
        if stop:
            self._proc.terminate()
        self._proc.join(timeout=5)
        self._conn = None


def stop() -> None:
    """Let a started helper that got no job go (a command that failed before it plotted)."""
    global _helper
    if _helper is not None:
        proc, conn = _helper
        _helper = None
        conn.close()
        proc.terminate()  # it holds nothing of ours; a fork may share the pipe, so do not wait on EOF
        proc.join(timeout=5)


def submit(fn: Callable, *args) -> Job:
    """fn(*args) in the helper if one was started, else here when ``result()`` is asked for."""
    return Job(fn, args)


def _serve(conn, command_end) -> None:
    """The helper: load matplotlib, draw a scrap figure, then run the one job sent.

    ``command_end`` is the command's end of the pipe, which the fork copied: it is closed here, so
    the command closing its end ends this one's ``recv``."""
    command_end.close()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the command's to handle
    try:
        _warm_up()
    except Exception:  # the job will report what is wrong
        pass
    try:
        fn, args = conn.recv()
    except (EOFError, OSError):
        return
    try:
        reply = (True, fn(*args))
    except Exception as exc:
        reply = (False, exc)
    try:
        conn.send(reply)
    except Exception as exc:  # a result or an error that does not pickle
        conn.send((False, RuntimeError(f"plot helper: {exc!r}")))


def _warm_up() -> None:
    import io

    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 1))
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1])
    ax.set_xlabel("t (s)")
    fig.savefig(io.BytesIO(), format="png", dpi=20)
