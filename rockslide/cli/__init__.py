"""The command line: a thin client of the Python API (`rockslide.api`).

Each command parses its options, calls the API (which conducts the study and writes its output
set, `outputs.OutputSet`) and prints what it returns. It imports neither `core`, `engine` nor
`analyses` (a contract in ``pyproject.toml``).

- `app`: the ``rockslide`` group, the error and exit-code policy (once for every command), the
  API's argument names as the command line's flags (`app.in_flags`);
- `console`: notes, progress bars, the command line a study stores;
- `run`: ``rockslide run`` and ``rockslide plot``;
- `studies`: ``rockslide sweep`` and ``rockslide fragility``;
- `tools`: ``info``, ``table1``, ``example``, ``criteria``;
- `risk`: ``rockslide risk``.
"""

from . import precision, risk, run, studies, tools  # noqa: F401  (each registers its commands on `main`)
from .app import entry, main

__all__ = ["entry", "main"]
