"""The test slider of the retiming tests (``tests/data/slider_x.toml``): a 2 kg carriage on a
rail along x, or along z against gravity, with Coulomb friction in its joint and a linear
motor with winding resistance and force constant on request."""

from __future__ import annotations

from pathlib import Path

DATA = Path(__file__).parent / "data"
MASS = 2.0  # the carriage [kg]
OHM, K_F = 2.0, 4.0  # the linear motor's winding resistance [ohm] and force constant [N/A]


def slider(folder: Path, vertical: bool, coulomb_N: float = 0.0, motor: bool = False) -> Path:
    """The slider's description written into ``folder``."""
    text = (DATA / "slider_x.toml").read_text()
    if vertical:
        text = (text.replace("axis = [1.0, 0.0, 0.0]", "axis = [0.0, 0.0, 1.0]")
                .replace('position = ["x"]', 'position = ["z"]').replace("x_m = 0.1", "z_m = 0.1"))
    if coulomb_N:
        text = text.replace("actuated = true", f"actuated = true\nfriction = {{ coulomb_force_N = {coulomb_N} }}")
    if motor:
        text += f'\n[[actuators]]\njoint = "P"\nwinding_resistance_ohm = {OHM}\nforce_constant_N_A = {K_F}\n'
    f = folder / ("vslider.toml" if vertical else "slider.toml")
    f.write_text(text)
    return f
