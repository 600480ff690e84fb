"""What the API's conductors share: a case from what was given, where a study computes, values
given as text or as SI numbers."""

from __future__ import annotations

import contextlib
import importlib
import threading
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import CaseError

if TYPE_CHECKING:
    from ..case import Case


def as_case(case) -> Case:
    """A Case from a Case, a mapping or a path (`case.load_case`)."""
    from ..case import Case, load_case  # with yaml: loaded by the conductors that take a case

    if isinstance(case, Case):
        return case
    if not isinstance(case, (Mapping, str, Path)):
        raise CaseError(f"expected a Case, a mapping or a case file's path, got {type(case).__name__}", source="case")
    return load_case(case)


def axis_text(values, kind: str) -> str:
    """An axis given as text (as on the command line) or as values of the unit kind ``kind``: a
    comma list, numbers in SI."""
    if isinstance(values, str):
        return values
    from ..units import SI_UNITS

    unit = SI_UNITS.get(kind, "") if kind != "dimensionless" else ""
    return ",".join(value if isinstance(value, str) else f"{float(value)!r}{unit}" for value in values)


def with_scale(case: Case, **values) -> Case:
    """``case`` at the scale values given (``pga``, ``vertical_factor``, ``amplitude``: one value
    each, SI or text with units), as a sweep's point at them (`analyses.sweep.axis_changes`)."""
    given = {name: value for name, value in values.items() if value is not None}
    if not given:
        return case
    for name, value in given.items():
        if not isinstance(value, (str, int, float)) or isinstance(value, bool):
            raise CaseError(f"expected one value (a number in SI, or a string with its unit), got "
                            f"{type(value).__name__}", source=name)
    from ..analyses import sweep as sw
    from ..case import case_with

    changes = {}
    for name, value in given.items():
        axis = sw.parse_axis(name, axis_text([value] if not isinstance(value, str) else value, sw.AXES[name].kind))
        if len(axis) != 1:
            raise CaseError(f"expected one value, got {len(axis)}", source=name)
        changes.update(sw.axis_changes(name, axis.values[0], case, None))
    return case_with(case, changes)


def check_where(*, workers=None, scheduler=None, device: str = "cpu", wait_workers=None, tls=None):
    """Where a study computes, checked before any planning (`engine.execute.check_where`): the
    scheduler found, or None."""
    from ..engine.execute import check_where as check

    whole(workers, "workers", optional=True)     # its range: `engine.execute.check_workers`
    real(wait_workers, "wait_workers", optional=True)
    if not isinstance(device, str):
        raise CaseError(f"expected 'cpu', 'gpu' or 'auto', got {type(device).__name__}", source="device")
    return check(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers, tls=tls)


def path_arg(value, name: str, *, optional: bool = True):
    """``value`` if it is a path (str or os.PathLike; None when ``optional``); else a `CaseError`
    naming the argument."""
    import os

    if value is None and optional:
        return None
    if isinstance(value, (str, os.PathLike)) and not isinstance(value, bytes):
        return value
    raise CaseError(f"expected a path (str or pathlib.Path), got {type(value).__name__}", source=name)


def whole(value, name: str, low: int | None = None, high: int | None = None, *, optional: bool = False):
    """``value`` as an int if it is a whole number within ``[low, high]``; else a `CaseError`."""
    import numbers

    if value is None and optional:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or \
            (low is not None and value < low) or (high is not None and value > high):
        bounds = f" within {low} ... {high}" if high is not None else f" >= {low}" if low is not None else ""
        raise CaseError(f"expected a whole number{bounds}, got {value!r}"[:200], source=name)
    return int(value)


def real(value, name: str, *, optional: bool = False):
    """``value`` as a float if it is a real number; else a `CaseError` naming the argument."""
    import numbers

    if value is None and optional:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise CaseError(f"expected a number, got {type(value).__name__}", source=name)
    return float(value)


def callable_arg(value, name: str):
    """``value`` if it is None or callable; else a `CaseError` naming the argument."""
    if value is not None and not callable(value):
        raise CaseError(f"expected a function (or None), got {type(value).__name__}", source=name)
    return value


def axis_values(values, name: str):
    """An axis given as text, or as values (a sequence, range or iterable of numbers or strings with
    units), bounded to the most values one axis may have before anything is built."""
    import itertools
    import numbers

    from ..engine.plan import MAX_POINTS

    if isinstance(values, str):
        return values
    if isinstance(values, (numbers.Number, bytes)) or not hasattr(values, "__iter__"):
        raise CaseError(f"expected text ('0.3:0.7:0.1', '0.3,0.5') or a sequence of values, got "
                        f"{type(values).__name__}", source=name)
    if hasattr(values, "__len__") and len(values) > MAX_POINTS:
        raise CaseError(f"{len(values)} values; at most {MAX_POINTS} on one axis", source=name)
    items = list(itertools.islice(values, MAX_POINTS + 1))
    if len(items) > MAX_POINTS:
        raise CaseError(f"more than {MAX_POINTS} values; at most {MAX_POINTS} on one axis", source=name)
    for item in items:
        if isinstance(item, bool) or not isinstance(item, (str, numbers.Real)):
            raise CaseError(f"expected numbers (SI) or strings with units, got {type(item).__name__}", source=name)
    return items


class Meanwhile:
    """``task()`` on a thread of its own, started at once, while the caller computes; `result`
    waits for it and gives its value or raises its exception. For the work on a study's outputs
    that needs nothing of what is being computed (the modules they are written with,
    `importing_meanwhile`; a run's history, written while its ensemble computes), only where
    `output_modules` allows a second thread (the build's machine code)."""

    def __init__(self, task, *, name: str = "rockslide-meanwhile"):
        self._value = self._error = None
        self._thread = threading.Thread(target=self._run, args=(task,), name=name, daemon=True)
        self._thread.start()

    def _run(self, task) -> None:
        try:
            self._value = task()
        except BaseException as exc:  # noqa: BLE001 - raised again by result(), in the caller's thread
            self._error = exc

    def result(self):
        """The task's value, once it is done; its exception raised here."""
        self._thread.join()
        if self._error is not None:
            raise self._error
        return self._value


@contextlib.contextmanager
def importing_meanwhile(modules: Sequence[str]):
    """Import ``modules`` on a thread of their own while the block runs; wait for it at the end.

    A study computes on threads that release the GIL (the build's machine code, numba's nogil
    kernels; a single run's kernel too) while the main thread only waits, so the modules its
    outputs need afterwards load in that time rather than after it: rockslide.io.results with
    h5py (0.05 s on the 2-core development machine), rockslide.plots with matplotlib (0.5 s). A
    module that fails to load here is loaded again where it is used, and its error said there.
    """
    def load() -> None:
        for name in modules:
            try:
                importlib.import_module(name)
            except Exception:  # noqa: BLE001 - the import where the module is used says what failed
                continue

    if not modules:
        yield
        return
    loader = Meanwhile(load, name="rockslide-imports")
    try:
        yield
    finally:
        loader.result()


def output_modules(outputs, *, device: str = "cpu", scheduler=None, analysis: Sequence[str] = ()) -> list[str]:
    """The modules a study's ``outputs`` (`outputs.OutputSet`, or None) are written with, and the
    modules its ``analysis`` of the results loads (`ANALYSIS_MODULES`), to load while it computes
    (`importing_meanwhile`): only where it computes locally on the build's machine code, whose
    threads import nothing and whose main thread only waits (numba's JIT, the GPU and a cluster
    import modules of their own meanwhile, which a second importing thread could meet in the
    opposite order)."""
    from ..engine.execute import on_machine_code

    if scheduler is not None or not on_machine_code(device):
        return []
    written = [] if outputs is None else ["rockslide.io.results"] + (["rockslide.plots"] if outputs.plot else [])
    return written + list(analysis)


#: What the analysis of a study's results loads that nothing loaded before it (`output_modules`):
#: numpy's quantiles, percentiles and medians import numpy.ma (through ``np.unique``; 20-30 ms on
#: the 2-core development machine), a fragility's bootstrap numpy.random (10-15 ms).
ANALYSIS_MODULES = {"ensemble": ("numpy.ma",), "fragility": ("numpy.ma", "numpy.random")}
