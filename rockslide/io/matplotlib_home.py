"""Where matplotlib keeps its configuration and font cache, settled before it is first imported
(`rockslide.plots` imports this module first; nothing here imports matplotlib).

With a read-only or missing HOME, matplotlib makes a temporary folder itself but says so in lines
on stderr, beside rockslide's one line; `settle` makes it quietly instead.
"""

from __future__ import annotations

import os
import sys


def settle() -> None:
    """Point ``MPLCONFIGDIR`` at a temporary folder (removed at exit) when matplotlib's default
    folders (``$XDG_CONFIG_HOME/matplotlib``, ``$XDG_CACHE_HOME/matplotlib``: under a read-only or
    missing HOME) cannot be written; otherwise matplotlib does the same but says so on stderr, in
    lines beside rockslide's own. Runs before matplotlib is first imported; a given
    ``MPLCONFIGDIR`` is left alone."""
    if os.environ.get("MPLCONFIGDIR") or "matplotlib" in sys.modules or os.name != "posix":
        return
    home = os.path.expanduser("~")
    for variable, fallback in (("XDG_CONFIG_HOME", ".config"), ("XDG_CACHE_HOME", ".cache")):
        folder = os.path.join(os.environ.get(variable) or os.path.join(home, fallback), "matplotlib")
        try:
            os.makedirs(folder, exist_ok=True)
            usable = os.access(folder, os.W_OK | os.X_OK)
        except OSError:
            usable = False
        if not usable:
            import atexit
            import shutil
            import tempfile

            temporary = tempfile.mkdtemp(prefix="rockslide-matplotlib-")
            atexit.register(shutil.rmtree, temporary, ignore_errors=True)
            os.environ["MPLCONFIGDIR"] = temporary
            return


settle()
