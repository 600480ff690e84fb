"""The command line: a thin client of the Python API (`rockslide.api`).

- `app`: the ``rockslide`` group, the error and exit-code policy (once for every command), the
  console's helpers;
- `run`: ``rockslide run`` and ``rockslide plot``;
- `studies`: ``rockslide sweep`` and ``rockslide fragility``;
- `tools`: ``info``, ``table1``, ``example``, ``criteria``;
- `risk`: ``rockslide risk``.
"""

from . import precision, risk, run, studies, tools  # noqa: F401  (each registers its commands on `main`)
from .app import entry, main

__all__ = ["entry", "main"]
