"""The shipped example, for a new user anywhere (``rockslide example``): its case file (package data,
``rockslide/example.yaml``) and its two synthetic records, made by `synthetic.example_pair`
exactly as ``records/make_example_records.py`` makes the copies in the repository."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .files import atomic_write, check_destination
from .records import write_at2
from .synthetic import example_pair

CASE_FILE = "example.yaml"
#: The example's records: file name, seed (in the title), component.
RECORDS = (("synthetic_kt_h.at2", 1995, "horizontal"), ("synthetic_kt_v.at2", 1996, "vertical"))
RECORD_DT = 0.01   # [s]


def case_text() -> str:
    """The example's case file (its records named as files beside it)."""
    return resources.files("rockslide").joinpath(CASE_FILE).read_text(encoding="utf-8")


def write_records(folder) -> list[Path]:
    """Write the example's records into ``folder`` (replacing them): PEER AT2 in g, 20 s at 0.01 s."""
    folder = Path(folder)
    paths = []
    for (name, seed, component), values in zip(RECORDS, example_pair(dt=RECORD_DT), strict=True):
        paths.append(write_at2(folder / name, values, RECORD_DT, component=component,
                               title=f"rockslide synthetic Kanai-Tajimi record, seed {seed}"))
    return paths


def write_example(folder, *, overwrite: bool = False) -> list[Path]:
    """Write ``folder/example.yaml`` and its records; nothing is written if one of the three exists
    and ``overwrite`` is false.

    Raises
    ------
    OutputError
        A file exists (without ``overwrite``), or the folder cannot be created or written.
    """
    folder = Path(folder)
    names = [CASE_FILE] + [name for name, _, _ in RECORDS]
    for name in names:
        check_destination(folder / name, overwrite=overwrite, example="example/example.yaml")
    with atomic_write(folder / CASE_FILE, overwrite=overwrite, mode="w", what="case file") as handle:
        handle.write(case_text())
    return [folder / CASE_FILE] + write_records(folder)
