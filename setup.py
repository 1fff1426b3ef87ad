"""Build step of pkmdyn: a wheel carries its numerical kernels compiled for the building machine.

After the sources are copied into the build folder, ``pkmdyn compile`` runs there once: numba
writes every kernel's compiled code into ``__pycache__`` beside its source in the build
folder, and the wheel (so the install) carries those files. numba stamps each cache entry with
a hash of its source file's content (numba 0.68 and newer), the CPU name and features and the
numba version, so the installed cache serves every later process on this machine with this
numba; anywhere else a command compiles what it misses and says so (``docs/performance.md``).
An editable install compiles nothing here (the kernels compile on first use, beside the
sources); ``PKMDYN_COMPILE_AT_INSTALL=0`` skips the step.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


#: the longest the build waits for the kernels' compilation [s] (about two minutes on two cores):
#: past it the install goes on, and the commands compile what is missing on first use
COMPILE_TIMEOUT_S = 1800


def _stop(proc: subprocess.Popen) -> None:
    """End ``proc`` and the lanes it started (its process group, where the system has them)."""
    if hasattr(os, "killpg"):
        os.killpg(proc.pid, signal.SIGKILL)
    else:  # pragma: no cover - no process groups
        proc.kill()
    proc.wait()


class BuildPyCompiled(build_py):
    """``build_py``, then ``pkmdyn compile`` on the build folder (module docstring)."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False) or os.environ.get("PKMDYN_COMPILE_AT_INSTALL", "1") == "0":
            return
        lib = Path(self.build_lib).resolve()
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}  # the cache beside the sources
        env["PYTHONDONTWRITEBYTECODE"] = "1"  # numba's cache in the wheel, not the build's own bytecode
        env["PYTHONPATH"] = os.pathsep.join([str(lib), *([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else [])])
        with tempfile.TemporaryDirectory(prefix="pkmdyn-build-") as cwd:
            # its own process group: stopped whole (its lanes included) when it takes too long
            proc = subprocess.Popen([sys.executable, "-m", "pkmdyn.cli", "compile"], env=env, cwd=cwd,
                                    start_new_session=True)
            try:
                proc.wait(timeout=COMPILE_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                _stop(proc)
                self.warn(f"pkmdyn compile took over {COMPILE_TIMEOUT_S} s and was stopped: the kernels it had not "
                          "compiled compile on their first use")
                return
            except BaseException:  # Ctrl-C: the lanes end with it
                _stop(proc)
                raise
        if proc.returncode != 0:
            self.warn("pkmdyn compile failed: the kernels it missed compile on their first use")


setup(cmdclass={"build_py": BuildPyCompiled})
