"""The package build compiles the numerical core, so that the first run after ``pip install`` starts
at once instead of compiling for a minute (issue 11; README, 'The first run').

Everything else about the package is in ``pyproject.toml``. After setuptools has laid out the
package (in its build folder, or in place for an editable install), `CompileCore` runs two steps
there, each in a child process:

1. `rockslide.core.build.precompile`: numba's cache of the core, in ``rockslide/core/__pycache__``,
   for the sweeps, the fragility analyses and the GPU path (numba's JIT). numba (0.68 on) keys that
   cache on the content of the source files, the numba version and the CPU, so it serves the
   installation on this machine as long as pip gives the build and the installation the same numba
   (it picks the newest for both). Whenever the cache does not fit, the first sweep compiles with a
   note.
2. `rockslide.core.native.build`: the entry points of a single run compiled ahead of time (numba's
   ``pycc``, for a generic CPU) into the extension module ``rockslide/core/_native``, which
   ``rockslide run`` uses without importing numba. It needs a C compiler; without one, runs use
   numba's JIT and its cache.

The wheel carries both, so it is marked as specific to the platform and Python it was built with.
``ROCKSLIDE_PRECOMPILE=0`` skips both steps; a step that fails leaves a warning, not a failed install.
"""

import os
import subprocess
import sys
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution

STEPS = (
    ("numba's cache of the numerical core", "from rockslide.core import build; build.precompile()"),
    ("the ahead-of-time module of a single run", "from rockslide.core import native; native.build()"),
)


class CompileCore(build_py):
    def run(self):
        super().run()
        if os.environ.get("ROCKSLIDE_PRECOMPILE", "1") == "0":
            return
        root = Path(__file__).resolve().parent if getattr(self, "editable_mode", False) else Path(self.build_lib)
        env = {key: value for key, value in os.environ.items() if key != "NUMBA_CACHE_DIR"}
        # pip's isolated build environment (numba among the build requirements) reaches the child
        # through PYTHONPATH: keep it, behind the package just laid out
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), os.environ.get("PYTHONPATH")]))
        for what, code in STEPS:
            print(f"rockslide: compiling {what} into {root / 'rockslide' / 'core'} (about a minute)", file=sys.stderr)
            if subprocess.run([sys.executable, "-c", code], cwd=root, env=env, check=False).returncode != 0:
                self.warn(f"rockslide: {what} could not be compiled at build time; runs will compile "
                          "with numba instead")


class CompiledDistribution(Distribution):
    """The wheel holds machine code (module docstring): tag it with the platform and Python ABI."""

    def has_ext_modules(self):
        return True


setup(cmdclass={"build_py": CompileCore}, distclass=CompiledDistribution)
