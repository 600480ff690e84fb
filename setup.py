"""The package build compiles the numerical core, so that the first run after ``pip install`` starts
in a second instead of compiling for a minute (issue 11; README, 'Set up').

Everything else about the package is in ``pyproject.toml``. After setuptools has laid out the
package (in its build folder, or in place for an editable install), `CompileCore` runs
`rockslide.core.compiled.precompile` there in a child process, which leaves numba's cache of the core
in ``rockslide/core/__pycache__``: the wheel carries it into the installation. numba (0.68 on) keys
that cache on the content of the source files, the numba version and the CPU, so it serves the
installation on this machine as long as pip gives the build and the installation the same numba (it
picks the newest for both). Whenever the cache does not fit, the first run compiles with a note.
``ROCKSLIDE_PRECOMPILE=0`` skips the step; a build whose compile fails still installs (with a
warning).
"""

import os
import subprocess
import sys
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


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
        print(f"rockslide: compiling the numerical core into {root / 'rockslide' / 'core'} "
              "(about a minute)", file=sys.stderr)
        done = subprocess.run([sys.executable, "-c", "from rockslide.core import compiled; compiled.precompile()"],
                              cwd=root, env=env, check=False)
        if done.returncode != 0:
            self.warn("rockslide: the numerical core could not be compiled at build time; "
                      "the first run will compile it")


setup(cmdclass={"build_py": CompileCore})
