"""Make the synthetic records shipped in this folder (run from the repository root):

    python records/make_example_records.py

They are the project's own data (no third-party record): Kanai-Tajimi / Clough-Penzien filtered
white noise with a Jennings envelope, seeded, at 0.01 s, written as PEER AT2 in g: the example's
pair (20 s; `rockslide/example.py` writes the same files, ``rockslide example``) and the six pairs
of the synthetic suite in `suite-synthetic/` (listed by `suite-synthetic.yaml`). See
`rockslide/synthetic.py` for the model and `records/README.md` for the files.
"""

from pathlib import Path

from rockslide.io.example import write_records, write_suite_records

HERE = Path(__file__).resolve().parent

if __name__ == "__main__":
    print("wrote", " and ".join(str(p) for p in write_records(HERE)))
    print("wrote", len(write_suite_records(HERE)), "records in", HERE / "suite-synthetic")
