"""Plot decimation: what a pixel column shows is kept, spikes included."""

import numpy as np

from patchgen.render.plotting import envelope


def test_envelope_keeps_every_columns_extremes_in_time_order():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 120, 12001)
    y = rng.standard_normal(t.size)
    y[7777] = 50.0  # a one-sample spike
    y[123] = -40.0
    te, ye = envelope(t, y, 800)
    assert te.size <= 2 * 800 + 2 and np.all(np.diff(te) > 0)
    assert te[0] == t[0] and te[-1] == t[-1]
    assert ye.max() == 50.0 and ye.min() == -40.0
    per = -(-t.size // 800)
    for k in range(0, -(-t.size // per), 7):  # every column's min and max are among the kept samples
        seg = y[k * per:(k + 1) * per]
        kept = ye[(te >= t[k * per]) & (te <= t[min((k + 1) * per, t.size) - 1])]
        assert seg.max() in kept and seg.min() in kept


def test_short_traces_and_gaps_are_kept_as_they_are():
    t = np.arange(100.0)
    y = np.sin(t)
    te, ye = envelope(t, y, 800)
    assert te is t and ye is y
    t = np.linspace(0, 1, 5000)
    y = np.cos(t)
    y[2500] = np.nan
    te, ye = envelope(t, y, 100)
    assert np.isnan(ye).sum() == 1 and te[np.isnan(ye)][0] == t[2500]
    assert np.nanmax(ye) == np.nanmax(y) and np.nanmin(ye) == np.nanmin(y)
