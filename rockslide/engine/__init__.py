"""The engine every analysis goes through: case -> checks -> kernel inputs -> chunks -> results.

- `ground`: the ground motion a block stands on (records read and scaled, two components turned
  to the block, a floor's motion, analytic pulses);
- `prepare`: a case's ground motion and every check that needs no computation (one set of checks
  for runs, sweeps, fragility, ensembles);
- `axes`: the axes of a study (what a sweep can vary; an axis read from its text);
- `plan`: a study as a flat list of cases' kernel inputs (`plan.Plan`), built by one assembler
  (`plan.case_inputs`, `plan.Supports`, `plan.assemble`), its definition key, the memory it needs;
- `outcomes`: every case's result variables from its final kernel state (the outcome table);
- `chunks`: finished chunks on disk (resumable) or in memory, each store made for one plan;
- `execute`: threads or the GPU; progress, Ctrl-C, free space, the first compile;
- `cluster`: the same on a dask.distributed cluster.
"""
