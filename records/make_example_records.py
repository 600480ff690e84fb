"""Make the synthetic records shipped in this folder (run from the repository root):

    python records/make_example_records.py

They are the project's own data (no third-party record): Kanai-Tajimi / Clough-Penzien filtered
white noise with a Jennings envelope, seeded, 20 s at 0.01 s, written as PEER AT2 in g. See
`rockslide/synthetic.py` for the model, `rockslide/example.py` for the files (``rockslide example``
writes the same ones beside the example case) and `records/README.md`.
"""

from pathlib import Path

from rockslide.example import write_records

HERE = Path(__file__).resolve().parent

if __name__ == "__main__":
    print("wrote", " and ".join(str(p) for p in write_records(HERE)))
