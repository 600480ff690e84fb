"""The Python API: cases, runs and studies from a notebook or a script.

Each study is conducted here, once, and the command line is a client of it: ``rockslide run``,
``sweep``, ``fragility`` and ``risk`` parse their options into these calls, hand them an output set
(`outputs.OutputSet`) and print what they return, so that both give the same numbers, bit for bit.
Without ``outputs`` nothing is written.

>>> import rockslide
>>> case = rockslide.load_case("configs/example.yaml")                     # doctest: +SKIP
>>> result = rockslide.run(case)                                            # doctest: +SKIP
>>> result.summary.verdict                                                  # doctest: +SKIP
'standing'
>>> grid = rockslide.sweep(case, mu="0.3:0.7:0.1", pga="200gal:800gal:200gal")   # doctest: +SKIP
>>> grid.overturned.sum().item()                                            # doctest: +SKIP

Units: every number given is SI (m, kg, s, m/s^2, rad) unless it is a string with its unit, as in
case files (``"0.3 g"``, ``"50 mm"``); every number returned is SI, and datasets say their units in
each variable's ``units`` attribute.

Modules: `runs` (`run`, `ensemble`, `RunResult`), `studies` (`sweep`, `fragility` and their
conductors `sweep_study`, `fragility_study`), `site` (`risk`), `stored` (`read_result`, `plot_results`,
`export_pelicun`, `describe_file`, `redraw`), `tools` (records, Table 1, criteria maps, the example),
`reports` (the printouts).
"""

from __future__ import annotations

import importlib

#: Each public name and the module it lives in (loaded on first use: ``rockslide --help`` and
#: ``import rockslide`` stay light).
_WHERE = {
    "Case": "..case", "case_with": "..case", "load_case": "..case", "Summary": "..core.simulate",
    "OutputSet": "..outputs", "check_name": "..outputs", "output_folder": "..outputs",
    "record_lines": ".reports", "json_ready": ".reports", "run_lines": ".reports", "run_payload": ".reports",
    "stored_lines": ".reports",
    "risk": ".site", "risk_analysis": ".site", "risk_outputs": ".site", "risk_study": ".site",
    "KEEP_HISTORY_ROWS": ".runs", "LONG_RUN": ".runs", "RunResult": ".runs", "ensemble": ".runs", "run": ".runs",
    "describe_file": ".stored", "export_pelicun": ".stored", "plot_results": ".stored", "read_result": ".stored",
    "redraw": ".stored",
    "StudyResult": ".studies", "fragility": ".studies", "fragility_study": ".studies", "retired_axis": ".studies",
    "sweep": ".studies", "sweep_study": ".studies",
    "criteria_map": ".tools", "describe_record": ".tools", "is_result_file": ".tools", "table1": ".tools",
    "write_example": ".tools", "work_precision": ".tools", "describe_mesh": ".tools", "is_mesh_file": ".tools",
}

#: The documented API (docs/api.md); the other names of `_WHERE` serve the command line.
__all__ = ["load_case", "case_with", "Case", "run", "RunResult", "Summary", "ensemble", "sweep", "fragility", "risk",
           "StudyResult", "sweep_study", "fragility_study", "risk_study", "risk_outputs", "OutputSet", "read_result",
           "export_pelicun", "plot_results", "describe_mesh", "work_precision"]


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(_WHERE[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rockslide.api' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_WHERE))
