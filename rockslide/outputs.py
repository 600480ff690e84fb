"""The output set of a run or a study: its files, written together or not at all.

A result is a set of files in one output folder named after the case: ``NAME.h5`` (``NAME.sweep.h5``,
``NAME.fragility.h5``, ``NAME.risk.h5``), its figure ``NAME.png`` unless no figure is asked for, and
optionally a table ``NAME.csv``. `OutputSet` holds the rules every command and the Python API
follow, once:

- **Checked before the work** (`OutputSet.check`): a complete set is not replaced without
  ``overwrite``; a figure without its result is another result's; a result without its figure is
  finished (its figure drawn) when it is the same study's.
- **One at a time** (`OutputSet.one_at_a_time`): two identical studies into one folder run one after
  the other (they would share, and remove, one chunk folder).
- **Together** (`OutputSet.staging`, `io.files.Staging`): every file is staged, then all are
  published in one short section; a figure left from an earlier result that the new one does not
  show is removed in the same section (`OutputSet.stale`).

A name is a name, not a path (`check_name`): nothing is written outside the output folder.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from pathlib import Path

from .errors import CaseError, OutputError

#: The suffix of each kind's result file before ``.h5`` (a run's has none).
SUFFIXES = {"run": "", "sweep": ".sweep", "fragility": ".fragility", "risk": ".risk"}


def check_name(name: str, *, source: str = "name") -> str:
    """``name`` if it can name files in an output folder: not empty, no folder separator, not
    ``.`` or ``..``, no NUL; else a `CaseError` naming ``source``."""
    text = str(name)
    if not text.strip() or text in (".", "..") or "/" in text or "\\" in text or "\x00" in text:
        raise CaseError(f"{text!r} is not a name: a name holds no folder (no '/', not '.' or '..'); "
                        "the output folder is chosen apart", source=source)
    return text


def output_folder(out_dir, case=None, *, default: Path | None = None, source: str = "out_dir") -> Path:
    """The output folder: ``out_dir`` if given, else the case's ``output.dir``, else ``default``
    (``~`` expanded)."""
    from .io.files import expand_user

    if out_dir is not None:
        return expand_user(out_dir, source=source)
    if case is not None:
        return expand_user(case.output.dir, source=f"{case.source}: output.dir")
    return Path(default if default is not None else ".")


@dataclass
class OutputSet:
    """The files of one result (module docstring).

    Parameters
    ----------
    folder : Path
        The output folder.
    name : str
        The result's name (the case's), a name and not a path (`check_name`).
    kind : {"run", "sweep", "fragility", "risk"}
        What the result is: names its files (``NAME.sweep.h5``...).
    overwrite : bool
        Replace an existing result.
    plot : bool
        Draw the figure ``NAME.png`` (without it, an earlier figure of the result replaced is
        removed: it showed that result).
    csv : bool
        Also write the table ``NAME.csv``.
    dpi : float, optional
        Resolution of the PNG figure (default `plots.DPI`).
    size : tuple, optional
        The figure's size [in] (`units.parse_figure_size`).
    """

    folder: Path
    name: str
    kind: str = "run"
    overwrite: bool = False
    plot: bool = True
    csv: bool = False
    dpi: float | None = None
    size: tuple | None = None

    def __post_init__(self):
        self.folder = Path(self.folder)
        check_name(self.name)

    @property
    def stem(self) -> str:
        return f"{self.name}{SUFFIXES[self.kind]}"

    @property
    def h5(self) -> Path:
        return self.folder / f"{self.stem}.h5"

    @property
    def png(self) -> Path:
        return self.folder / f"{self.stem}.png"

    @property
    def table(self) -> Path:
        return self.folder / f"{self.stem}.csv"

    @property
    def example(self) -> str:
        return f"out/case{SUFFIXES[self.kind]}"

    def check(self, *, leftovers: bool = False) -> bool:
        """Check the set before the work.

        Returns True when, without ``overwrite``, ``NAME.h5`` exists but its set is not complete
        (its figure is missing, or ``leftovers`` of its computation remain): the caller decides
        whether it is this study's result and finishes it (else `refuse`). False when the work is
        to be done (nothing there, or ``overwrite``).

        Raises
        ------
        OutputError
            Without ``overwrite``: the complete set exists, or ``NAME.png`` exists without its
            ``NAME.h5`` (a figure of another result).
        """
        from .io import files

        files.check_destination(self.h5, overwrite=True, example=f"{self.example}.h5")
        files.check_destination(self.png, overwrite=True, example=f"{self.example}.png")
        if self.overwrite:
            return False
        if not _present(self.h5):
            files.refuse_existing(self.png, overwrite=False)
            return False
        if (not self.plot or _present(self.png)) and not leftovers:
            self.refuse()
        return True

    def refuse(self) -> None:
        """The `OutputError` of an existing ``NAME.h5`` (it is not this study's, or complete)."""
        from .io import files

        files.refuse_existing(self.h5, overwrite=False)

    def check_extra(self, path: Path, example: str) -> Path:
        """Check a further file of the set (an export) before the work."""
        from .io import files

        files.check_destination(path, overwrite=self.overwrite, example=example)
        return path

    def remove_stale_temporaries(self) -> None:
        """Remove what a killed writer of this set left (`files.remove_stale_temporaries`)."""
        from .io import files

        files.remove_stale_temporaries([self.h5, self.png])

    @contextlib.contextmanager
    def one_at_a_time(self, what: str, *, shard: bool = False):
        """Hold the lock of this set (``.NAME.h5.lock`` beside it) for the block, so that two
        identical studies into one folder run one after the other; yields a list that holds True
        when another one had it first (the outputs are then to be checked again). The shards of
        one study (``shard``) share it: they run at once, and a study that collects waits for them."""
        from .io import files

        waited: list[bool] = []
        lock = self.h5.with_name(f".{self.h5.name}.lock")
        with files.exclusive(lock, waiting_for=f"another {what} writing {self.h5}", waited=lambda: waited.append(True),
                             shared=shard):
            yield waited

    def staging(self):
        """A `files.Staging` for this set's files."""
        from .io.files import Staging

        return Staging(overwrite=self.overwrite)

    def save_figure(self, figure, staging, path: Path | None = None) -> None:
        """Stage ``figure`` as ``NAME.png`` (or ``path``)."""
        from .plots import save_figure

        save_figure(figure, self.png if path is None else path, overwrite=self.overwrite, dpi=self.dpi,
                    staging=staging)

    def write_csv(self, dataset, dims, staging) -> None:
        """Stage the tidy table of a study (`io.datasets.tidy_table`) as ``NAME.csv``."""
        from .io.datasets import tidy_table
        from .io.files import atomic_write

        with atomic_write(self.table, overwrite=self.overwrite, mode="w", what="table", staging=staging) as handle:
            handle.write(tidy_table(dataset, dims))

    def stale(self, staging, *, format: str | None = None) -> list[Path]:
        """The figure to remove when the set is published: with no figure asked for, ``NAME.png``,
        unless the result it was published with (the ``NAME.h5`` being replaced) holds the same
        results as the new one (`results.same_results`, for the study files of ``format``): a
        figure must not stand beside results it does not show, but rerunning the same study for
        its printout keeps its figure."""
        if self.plot or not _present(self.png):
            return []
        if format is None:
            return [self.png]
        from .io import results

        new = next(tmp for tmp, path in staging.items if Path(path) == self.h5)
        try:
            same = results.same_results(results.read_dataset(self.h5, format=format),
                                        results.read_dataset(new, format=format))
        except OutputError:             # no result beside it, or another kind: the figure is not its
            same = False
        return [] if same else [self.png]

    def written(self) -> str:
        """``out/a.h5, out/a.png and out/a.csv``: the files of the set, as printed."""
        names = [str(self.h5), *([str(self.png)] if self.plot else []), *([str(self.table)] if self.csv else [])]
        return ", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else names[0]

    def files(self) -> dict:
        """``{"hdf5": ..., "png": ... or None}``, as the JSON printouts give them."""
        return {"hdf5": str(self.h5), "png": str(self.png) if self.plot else None}


def _present(path: Path) -> bool:
    return path.exists() or path.is_symlink()
