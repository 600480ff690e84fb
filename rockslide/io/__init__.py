"""Files: one home per format.

- `files`: atomic writes, staging and publication of result sets, free space;
- `records`: accelerograms (AT2, K-NET, columns, values, obspy's formats);
- `results`: result, sweep and fragility files (HDF5, netCDF-4 data model);
- `datasets`: results as xarray Datasets;
- `hazard`: hazard curves (OpenQuake's CSV, plain tables), fragility tables;
- `cosmos`: COSMOS V1/V2 records;
- `pelicun`: fragility curves as pelicun's CSV and JSON;
- `mesh`: a scanned object's planar bodies (OBJ, STL, PLY, with trimesh);
- `synthetic`, `example`: the records and example files the project makes itself.
"""
