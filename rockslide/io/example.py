"""The shipped example, for a new user anywhere (``rockslide example``): its case file (package data,
``rockslide/example.yaml``) and its two synthetic records, made by `synthetic.example_pair`
exactly as ``records/make_example_records.py`` makes the copies in the repository; the synthetic
record suite (``suite-synthetic.yaml`` and its records, `synthetic.suite_pair`) for
``rockslide fragility``; a pulse case (``spectrum-one-sine.yaml``) for overturning spectra; and a
made-up hazard curve in OpenQuake's CSV layout (``hazard-example-PGA.csv``) for ``rockslide risk``.
The YAML files are package data, identical to the repository's ``configs/example.yaml``,
``records/suite-synthetic.yaml`` and ``configs/spectrum-one-sine.yaml`` (a test says so)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .files import Staging, atomic_write, check_destination
from .records import write_at2
from .synthetic import SUITE, example_pair, suite_pair

CASE_FILE = "example.yaml"
SUITE_FILE = "suite-synthetic.yaml"
SPECTRUM_FILE = "spectrum-one-sine.yaml"
#: A made-up hazard curve in OpenQuake's hazard-curve CSV layout, for ``rockslide risk``.
HAZARD_FILE = "hazard-example-PGA.csv"
#: A case of a body given by its mesh (`ROCK_FILE`) on the example's records.
ROCK_CASE_FILE = "rock.yaml"
#: The example's records: file name, seed (in the title), component.
RECORDS = (("synthetic_kt_h.at2", 1995, "horizontal"), ("synthetic_kt_v.at2", 1996, "vertical"))
RECORD_DT = 0.01   # [s]


def case_text(name: str = CASE_FILE) -> str:
    """A shipped text file: the example's case file (its records named as files beside it), the
    suite file, the spectrum case or the hazard curve."""
    return resources.files("rockslide").joinpath(name).read_text(encoding="utf-8")


def write_records(folder, staging=None) -> list[Path]:
    """Write the example's records into ``folder`` (replacing them): PEER AT2 in g, 20 s at 0.01 s."""
    folder = Path(folder)
    paths = []
    for (name, seed, component), values in zip(RECORDS, example_pair(dt=RECORD_DT), strict=True):
        paths.append(write_at2(folder / name, values, RECORD_DT, component=component, staging=staging,
                               title=f"rockslide synthetic Kanai-Tajimi record, seed {seed}"))
    return paths


def suite_record_names() -> list[str]:
    """The synthetic suite's record files, relative to the suite file's folder."""
    return [f"suite-synthetic/{name}_{part}.at2" for name in SUITE for part in ("h", "v")]


def write_suite_records(folder, staging=None) -> list[Path]:
    """Write the synthetic suite's records into ``folder/suite-synthetic`` (replacing them)."""
    records = Path(folder) / "suite-synthetic"
    records.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, (seed, *_) in SUITE.items():
        for values, part, component, record_seed in zip(suite_pair(name), ("h", "v"), ("horizontal", "vertical"),
                                                        (seed, seed + 100), strict=True):
            paths.append(write_at2(records / f"{name}_{part}.at2", values, RECORD_DT, component=component,
                                   title=f"rockslide synthetic suite record {name}, seed {record_seed}",
                                   staging=staging))
    return paths


#: A rock-like body as a mesh (``rockslide info example/rock.obj --units m``; docs/meshes.md).
ROCK_FILE = "rock.obj"


def rock_obj(b1: float = 0.044, b2: float = 0.129, h: float = 0.294, depth: float = 0.2) -> str:
    """A closed OBJ mesh [m] whose planar body along x (east) is model-asymmetric.md's rock: a prism
    of parallelogram section leaning toward -x, its base ``b1 + b2`` wide and its centre of mass
    ``h`` above the base, ``b1`` from the base's -x edge (pivot 1) and ``b2`` from its +x edge."""
    width, height = b1 + b2, 2.0 * h
    lean = 2.0 * b1 - width                       # the top's shift: the centre of mass at x = b1
    corners = [(0, 0, 0), (width, 0, 0), (width, depth, 0), (0, depth, 0),
               (lean, 0, height), (width + lean, 0, height), (width + lean, depth, height), (lean, depth, height)]
    faces = [(1, 3, 2), (1, 4, 3), (5, 6, 7), (5, 7, 8), (1, 2, 6), (1, 6, 5), (4, 7, 3), (4, 8, 7),
             (1, 5, 8), (1, 8, 4), (2, 3, 7), (2, 7, 6)]          # each counter-clockwise seen from outside
    lines = ["# rockslide's example rock: the planar body of docs/asymmetric.md along x (units: m)"]
    lines += [f"v {x:.6g} {y:.6g} {z:.6g}" for x, y, z in corners]
    lines += [f"f {a} {b} {c}" for a, b, c in faces]
    return "\n".join(lines) + "\n"


def write_example(folder, *, overwrite: bool = False) -> list[Path]:
    """Write ``folder/example.yaml`` and its records, ``folder/suite-synthetic.yaml`` and its
    records, ``folder/spectrum-one-sine.yaml``, ``folder/hazard-example-PGA.csv``,
    ``folder/rock.obj`` (`rock_obj`) and ``folder/rock.yaml`` (its case), published
    together (`files.Staging`): nothing is written if one of them exists and ``overwrite`` is
    false, and after Ctrl-C or an error the folders this made are removed again.

    Raises
    ------
    OutputError
        A file exists (without ``overwrite``), or the folder cannot be created or written.
    """
    folder = Path(folder)
    texts = (CASE_FILE, SUITE_FILE, SPECTRUM_FILE, HAZARD_FILE, ROCK_CASE_FILE)
    names = [*texts, ROCK_FILE, *(name for name, _, _ in RECORDS), *suite_record_names()]
    made = [path for path in (*reversed(folder.parents), folder, folder / "suite-synthetic") if not path.exists()]
    try:
        for name in names:
            check_destination(folder / name, overwrite=overwrite, example="example/example.yaml")
        with Staging(overwrite=overwrite) as staging:
            for name in texts:
                with atomic_write(folder / name, overwrite=overwrite, mode="w", what="case file",
                                  staging=staging) as handle:
                    handle.write(case_text(name))
            with atomic_write(folder / ROCK_FILE, overwrite=overwrite, mode="w", what="mesh",
                              staging=staging) as handle:
                handle.write(rock_obj())
            paths = ([folder / name for name in texts] + [folder / ROCK_FILE] + write_records(folder, staging)
                     + write_suite_records(folder, staging))
            staging.publish()
    except BaseException:
        for path in reversed(made):
            try:
                path.rmdir()            # only if empty: never what was there before
            except OSError:
                pass
        raise
    return paths
