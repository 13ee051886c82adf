"""The whole swing-up manoeuvre drawn: s, theta and force from hanging to the patched hold, the
hand-off and the limit switches named (patchgen.swingup.manoeuvre computes it)."""

from __future__ import annotations

from patchgen.swingup.manoeuvre import Manoeuvre


def plot_manoeuvre(m: Manoeuvre, stem: str, title: str, svg: bool = False) -> dict[str, bytes]:
    """s, theta and force over the whole manoeuvre, the hand-off marked.

    Parameters
    ----------
    m : Manoeuvre
        The manoeuvre.
    stem, title : str
        File name stem and the plot's title.
    svg : bool
        Also a deterministic ``<stem>.svg``.

    Returns
    -------
    dict of str to bytes
        ``<stem>.png`` (and ``<stem>.svg``), for the all-or-nothing writer.
    """
    from patchgen.render import plotting

    return plotting.rendered(manoeuvre_figure(m, title), stem, svg)


def manoeuvre_figure(m: Manoeuvre, title: str):
    """The manoeuvre's figure: pump-up and patched hold in two colours, the limit switches and
    the hand-off named in a legend above each panel; theta as plotting.THETA_LABEL."""
    from patchgen.render import plotting

    p = m.pump
    t0 = p.handoff_time if p.reached else p.t[-1]
    keep = p.t <= t0
    fig, ax = plotting.stacked(8, 7, 3, top_in=0.6, left_in=1.0, hspace=0.3)
    cols = plotting.columns(fig)
    env = lambda t, y: plotting.envelope(t, y, cols)
    ax[0].plot(*env(p.t[keep], p.x[keep, 0]), color="C0", label="pump-up")
    ax[1].plot(*env(*plotting.theta_degrees(p.t[keep], p.x[keep, 1])), color="C0", label="_pump-up")
    ax[2].plot(*env(p.t[keep], p.u[keep]), color="C0", label="_pump-up")
    if m.hold is not None:
        h = m.hold.history
        t = h["t"] + t0
        ax[0].plot(*env(t, h["s"]), color="C1", label="patched controller (bench)")
        ax[1].plot(*env(*plotting.theta_degrees(t, h["theta"])), color="C1", label="_hold")
        ax[2].plot(*env(t, h["force"]), color="C1", label="_hold")
    half = p.plant.d / 2
    for k, v in enumerate((-half, half)):
        ax[0].axhline(v, color="r", lw=0.6, ls="--", label="_" if k else f"limit switches ±{half:.3g} m")
    for a in ax:
        a.axvline(t0, color="k", lw=0.6, ls=":", label=f"hand-off {t0:.2f} s" if p.reached else f"end {t0:.2f} s")
        a.grid(alpha=0.3)
        plotting.legend_above(a, fontsize=8)
    ax[0].set_ylabel("s (m)")
    ax[1].set_ylabel(plotting.THETA_LABEL)
    plotting.full_circle(ax[1])
    ax[2].set_ylabel("force (N)")
    ax[2].set_xlabel("t (s)")
    fig.suptitle(title, fontsize=10, y=1 - 0.12 / fig.get_figheight())
    return fig
