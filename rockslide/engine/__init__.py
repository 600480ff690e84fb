"""The engine every analysis goes through: case -> checks -> kernel inputs -> chunks -> results.

- `prepare`: a case's ground motion read and scaled, and every check that needs no computation
  (one set of checks for runs, sweeps, fragility and what comes next);
- `plan`: a study as a flat list of cases' kernel inputs (`plan.Plan`), its definition key;
- `chunks`: finished chunks on disk (resumable) or in memory;
- `execute`: threads, the GPU or a dask cluster; progress, Ctrl-C, free space, the first compile.
"""
