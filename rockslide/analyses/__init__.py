"""Analyses: each one engine plan (`engine.plan.Plan`) plus its statistics and figures.

- `sweep`: grids over a case's values (and overturning spectra of pulses);
- `fragility`: record suites scaled to levels of an intensity measure, lognormal fits;
- `table1`: the paper's Table 1 and Figures 5-10.
"""
