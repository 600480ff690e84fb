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
conductors `sweep_study`, `fragility_study`), `risk`, `stored` (`read_result`, `plot_results`,
`export_pelicun`, `describe_file`, `redraw`), `tools` (records, Table 1, criteria maps, the example),
`reports` (the printouts).
"""

from __future__ import annotations

from ..case import Case, case_with, load_case
from ..core.simulate import Summary
from ..outputs import OutputSet, check_name, output_folder
from .reports import record_lines, run_lines, run_payload, stored_lines
from .risk import risk, risk_analysis, risk_outputs, risk_study
from .runs import KEEP_HISTORY_ROWS, LONG_RUN, RunResult, ensemble, run
from .stored import describe_file, export_pelicun, plot_results, read_result, redraw
from .studies import StudyResult, fragility, fragility_study, retired_axis, sweep, sweep_study
from .tools import criteria_map, describe_record, is_result_file, table1, write_example

__all__ = ["load_case", "case_with", "run", "sweep", "fragility", "ensemble", "risk", "read_result", "plot_results",
           "export_pelicun", "RunResult", "Case", "Summary", "StudyResult", "OutputSet", "sweep_study",
           "fragility_study", "risk_study", "risk_analysis", "describe_file", "redraw", "describe_record",
           "is_result_file", "table1", "criteria_map", "write_example", "output_folder", "check_name", "run_lines",
           "run_payload", "record_lines", "stored_lines", "KEEP_HISTORY_ROWS", "LONG_RUN", "retired_axis",
           "risk_outputs"]
