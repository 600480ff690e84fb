"""Make the synthetic records shipped in this folder (run from the repository root):

    python records/make_example_records.py

They are the project's own data (no third-party record): Kanai-Tajimi / Clough-Penzien filtered
white noise with a Jennings envelope, seeded, 20 s at 0.01 s, written as PEER AT2 in g. See
`rockslide/synthetic.py` for the model and `records/README.md` for the files.
"""

from pathlib import Path

from rockslide.records import write_at2
from rockslide.synthetic import example_pair

HERE = Path(__file__).resolve().parent

if __name__ == "__main__":
    horizontal, vertical = example_pair()
    write_at2(HERE / "synthetic_kt_h.at2", horizontal, 0.01,
              title="rockslide synthetic Kanai-Tajimi record, seed 1995", component="horizontal")
    write_at2(HERE / "synthetic_kt_v.at2", vertical, 0.01,
              title="rockslide synthetic Kanai-Tajimi record, seed 1996", component="vertical")
    print("wrote", HERE / "synthetic_kt_h.at2", "and", HERE / "synthetic_kt_v.at2")
