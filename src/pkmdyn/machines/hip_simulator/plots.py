"""Plots of the hip simulator in the style of the paper's figures (matplotlib, Agg backend)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ...profiles.orientation import OrientationMotion  # noqa: E402

__all__ = ["plot_motion_and_load", "plot_slider_motion", "plot_torque_parts", "plot_torques", "plot_friction_vs_load"]

_LEG_COLOURS = ("tab:blue", "tab:orange", "tab:green")


def plot_motion_and_load(motion: OrientationMotion, path: Path) -> Path:
    """Fig. 4 style: (a) the three Euler angles [deg], (b) the load [N] over time."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    for k, label in enumerate(("FE (alpha)", "AA (beta)", "IER (gamma)")):
        ax1.plot(motion.t, np.rad2deg(motion.angles[:, k]), label=label)
    ax1.set(xlabel="t [s]", ylabel="angle [deg]", title="(a) Motion")
    ax1.legend()
    ax1.grid(alpha=0.3)
    ax2.plot(motion.t, motion.load, color="tab:red")
    ax2.set(xlabel="t [s]", ylabel="load F [N]", title="(b) Load")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_slider_motion(t: np.ndarray, L: np.ndarray, Ld: np.ndarray, Ldd: np.ndarray, path: Path) -> Path:
    """Fig. 6 style: displacement [mm], velocity [mm/s], acceleration [mm/s^2] of all sliders.

    ``L, Ld, Ldd (n, 2, 3)`` [m, m/s, m/s^2], [sample, platform, leg]. The two sliders of one
    screw share velocity and acceleration, so panels (b) and (c) show one curve per screw.
    """
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    quantities = (
        (L, "displacement L [mm]", "(a) Displacement"),
        (Ld, "velocity dL/dt [mm/s]", "(b) Velocity"),
        (Ldd, "acceleration d2L/dt2 [mm/s^2]", "(c) Acceleration"),
    )
    for ax, (q, ylabel, title) in zip(axes, quantities):
        platforms = (0, 1) if ax is axes[0] else (1,)
        for j in platforms:
            for i in range(3):
                style = "-" if j == 0 else "--"
                label = f"S{j + 1}{i + 1}" if ax is axes[0] else f"S1{i + 1}, S2{i + 1}"
                ax.plot(t, 1e3 * q[:, j, i], style, color=_LEG_COLOURS[i], label=label)
        ax.set(xlabel="t [s]", ylabel=ylabel, title=title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_torque_parts(t: np.ndarray, parts: dict[str, np.ndarray], path: Path) -> Path:
    """Fig. 8 style: one panel per part, three motors each; torques in N mm as in the paper."""
    names = list(parts)
    fig, axes = plt.subplots(1, len(names), figsize=(4.2 * len(names), 4))
    for ax, name in zip(np.atleast_1d(axes), names):
        for i in range(3):
            ax.plot(t, 1e3 * parts[name][:, i], color=_LEG_COLOURS[i], label=f"motor {i + 1}")
        ax.set(xlabel="t [s]", ylabel="torque [N mm]", title=name)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_torques(t: np.ndarray, tau: np.ndarray, path: Path) -> Path:
    """Fig. 11 style: the total driving torque of each motor [N mm]."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for i, ax in enumerate(axes):
        ax.plot(t, 1e3 * tau[:, i], color=_LEG_COLOURS[i])
        ax.set(xlabel="t [s]", ylabel="torque [N mm]", title=f"({'abc'[i]}) Linear module {i + 1}")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_friction_vs_load(t: np.ndarray, load: np.ndarray, tau_friction: np.ndarray, path: Path) -> Path:
    """Friction torque per motor [N mm]: (a) with the load over the cycle, (b) against the load."""
    fig, (ax, ax3) = plt.subplots(1, 2, figsize=(13, 4.2))
    for i in range(3):
        ax.plot(t, 1e3 * tau_friction[:, i], color=_LEG_COLOURS[i], label=f"friction, motor {i + 1}")
    ax.set(xlabel="t [s]", ylabel="friction torque [N mm]", title="(a) Over the cycle")
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(t, load, color="tab:red", alpha=0.5, label="load")
    ax2.set_ylabel("load F [N]")
    lines = ax.get_legend_handles_labels()
    lines2 = ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], fontsize=8, loc="upper right")
    for i in range(3):
        ax3.plot(load, 1e3 * np.abs(tau_friction[:, i]), ".", ms=2, color=_LEG_COLOURS[i], label=f"motor {i + 1}")
    ax3.set(xlabel="load F [N]", ylabel="|friction torque| [N mm]", title="(b) Against the load")
    ax3.grid(alpha=0.3)
    ax3.legend(fontsize=8, markerscale=4)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
