"""What the API's conductors share: a case from what was given, where a study computes, values
given as text or as SI numbers."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from ..case import Case, load_case
from ..errors import CaseError


def as_case(case) -> Case:
    """A Case from a Case, a mapping or a path (`load_case`)."""
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

    return check(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers, tls=tls)
