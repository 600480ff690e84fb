"""rockslide: nonlinear seismic response of free-standing rectangular rigid blocks.

Rest, slip, liftoff (rocking with impacts), liftoff-slip interaction and overturning of a block on a
rigid foundation shaken horizontally and vertically, after Taniguchi (the paper in the README).

The Python API (`rockslide.api`, loaded on first use so that ``import rockslide`` stays cheap):

- `load_case` (a case file or a mapping), `case_with` / ``Case.with_``;
- `run` -> `RunResult` (``.summary``, ``.history``, ``.events``, ``.to_xarray()``);
- `sweep`, `fragility` and `ensemble` (a verdict's neighbourhood) -> ``xarray.Dataset``;
- `risk`: a fragility over a site's hazard curves -> annual rates (``xarray.Dataset``);
- `read_result`: any file rockslide writes;
- `plot_results`: the figure of a result, or of several of one kind overlaid (``size="column"``...).
- `export_pelicun`: a fragility as a row of pelicun's fragility CSV and its JSON metadata.
"""

from ._version import __version__

__all__ = ["__version__", "load_case", "case_with", "run", "sweep", "fragility", "ensemble", "risk", "read_result",
           "plot_results", "export_pelicun", "RunResult"]

_API = {"load_case", "case_with", "run", "sweep", "fragility", "ensemble", "risk", "read_result", "plot_results",
        "export_pelicun", "RunResult", "Case", "Summary"}


def __getattr__(name: str):
    if name in _API:
        from . import api
        return getattr(api, name)
    raise AttributeError(f"module 'rockslide' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | _API)
