"""Dissipation-efficiency figures of a driven box (the 2023 paper): ``⟨E_d⟩ / m`` versus drive
amplitude (:func:`efficiency_figure`) and phase-resolved panels over one drive period
(:func:`phase_figure`). Data: :class:`jaxdamp.studies.efficiency.EfficiencyResult`."""

from __future__ import annotations

import numpy as np

from jaxdamp.figures.style import FIGSIZE, figure


def efficiency_figure(curves, title=""):
    """``⟨E_d⟩ / m`` versus drive amplitude (the 2023 paper's figs. 2, 6, 9).

    Args:
      curves: ``[(label, amplitudes [m] (P,), E_d/m [1/kg] (P,), spread [1/kg] (P,)), ...]``;
        the spread is drawn as error bars (the paper: standard deviation over periods).
    """
    fig = figure(FIGSIZE["efficiency"])
    ax = fig.subplots()
    for label, amp, y, err in curves:
        ax.errorbar(np.asarray(amp) * 100, y, yerr=err, fmt="o-", ms=4, capsize=2, label=label)
    ax.set_xlabel("drive amplitude A_d [cm]")
    ax.set_ylabel("⟨E_d⟩ / m  [1/kg]")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def phase_figure(cases, title=""):
    """Phase-resolved diagnostics over one drive period (the paper's figs. 4, 5, 7, 8, 10–12).

    Args:
      cases: ``[(label, phase dict, species names), ...]`` with the arrays of one point of
        :attr:`jaxdamp.studies.efficiency.EfficiencyResult.phase` (``phase``, ``contacts``,
        ``force_floor_lid``, ``z_cm_species``, ``vz_cm_species``, ``z_box``).
    Panels: grains touching floor or lid; vertical force of the grains on floor + lid; the
    centre of mass' phase plot ``v_z(z)`` per species, ``z`` measured from the box's mid-plane
    position at rest (lab frame).
    """
    fig = figure(FIGSIZE["phase"])
    axes = fig.subplots(1, 3)
    styles = ["-", "--", ":", "-."]

    def close(a):  # a closed orbit
        return np.append(a, a[:1])

    for k, (label, ph, names) in enumerate(cases):
        x = np.asarray(ph["phase"])
        line, = axes[0].plot(x, ph["contacts"], label=label)
        axes[1].plot(x, ph["force_floor_lid"], color=line.get_color(), label=label)
        zc, vc = np.asarray(ph["z_cm_species"]), np.asarray(ph["vz_cm_species"])
        for s, name in enumerate(names):
            axes[2].plot(close(zc[:, s]) * 100, close(vc[:, s]), styles[s % 4],
                         color=line.get_color(), label=f"{label}: {name}")
    axes[0].set_ylabel("grains touching floor or lid")
    axes[1].set_ylabel("vertical force on floor + lid [N]")
    for ax in axes[:2]:
        ax.set_xlabel("phase t/T (box at its top at 0, z_box = A_d cos 2πft)")
    axes[2].set_xlabel("centre of mass z [cm] (lab frame)")
    axes[2].set_ylabel("centre of mass v_z [m/s]")
    for ax in axes:
        ax.legend(fontsize=6)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig
