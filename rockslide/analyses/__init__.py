"""Analyses: each one engine plan (`engine.plan.Plan`) plus its statistics and figures.

- `sweep`: grids over a case's values (and overturning spectra of pulses);
- `fragility`: record suites scaled to levels of an intensity measure, the fitted and shape-free
  curves, surfaces on two measures;
- `goodness`: the statistics of fragility curves (goodness of fit, isotonic curves, probit surfaces);
- `measures`: the intensity measures (``--im``) a fragility and a hazard curve are functions of;
- `ensemble`: a verdict's neighbourhood (members drawn over what is uncertain);
- `risk`: a fragility over a site's hazard curves, to annual rates;
- `table1`: the paper's Table 1 and Figures 5-10;
- `kinds`: the study kinds, registered once (file format, figures of files read back).
"""
