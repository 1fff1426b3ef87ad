"""Plots of an identification: measured against identified torques, and the residuals."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

__all__ = ["plot_torque_fit", "plot_residuals"]

Array = NDArray[np.float64]


def plot_torque_fit(t: Array, measured: Array, identified: Array, path: Path) -> Path:
    """Measured and identified torques ``(n, nu)`` [N m] per actuator, in N mm."""
    nu = measured.shape[1]
    fig, axes = plt.subplots(nu, 1, figsize=(9, 2.6 * nu), sharex=True)
    for i, ax in enumerate(np.atleast_1d(axes)):
        ax.plot(t, 1e3 * measured[:, i], lw=0.8, color="0.5", label="measured")
        ax.plot(t, 1e3 * identified[:, i], lw=1.2, color="tab:blue", label="identified model")
        ax.set(ylabel=f"tau{i + 1} [N mm]")
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[0].legend(loc="upper right")
    np.atleast_1d(axes)[-1].set(xlabel="t [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_residuals(t: Array, residual: Array, path: Path) -> Path:
    """Residuals (measured - identified) ``(n, nu)`` [N m] per actuator, in N mm."""
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for i in range(residual.shape[1]):
        ax.plot(t, 1e3 * residual[:, i], lw=0.8, label=f"motor {i + 1}")
    ax.set(xlabel="t [s]", ylabel="measured - identified [N mm]")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
