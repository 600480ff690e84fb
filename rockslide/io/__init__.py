"""Files: one home per format.

- `files`: atomic writes, staging and publication of result sets, free space;
- `records`: accelerograms (AT2, K-NET, columns, values, obspy's formats);
- `results`: result, sweep and fragility files (HDF5, netCDF-4 data model);
- `datasets`: results as xarray Datasets;
- `synthetic`, `example`: the records and example files the project makes itself.
"""
