"""Intensity measures of a record (``--im``): what a fragility analysis scales its records to, and
what a fragility curve and a hazard curve are functions of (`risk`). Apart from
`analyses.fragility` so that ``rockslide risk`` of a given fragility loads neither the engine nor the
fragility analysis (0.1 s of the command)."""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

import numpy as np

from ..errors import CaseError
from ..units import STANDARD_GRAVITY, parse_quantity

__all__ = ["IntensityMeasure", "INTENSITY_MEASURES", "parse_im", "SA_PERIODS"]


@dataclass(frozen=True)
class IntensityMeasure:
    """An intensity measure of the horizontal record.

    Attributes
    ----------
    name : str
        ``pga``, ``pgv``, ``pga_rocking``, ``pfa``, ``pfv`` or ``sa(T)`` (as ``sa(0.5 s)``).
    kind : str
        Unit kind of its levels (a key of `units.UNITS`).
    units : str
        Its SI unit (``1`` when dimensionless).
    long_name : str
        What it is, in words.
    label : str
        Its symbol in figures (``PGA``, ``Sa(0.5 s, 5 %)``).
    display_unit : str
        Unit of figures and messages (``g``, ``cm/s``; empty when dimensionless);
        ``display_scale`` is its size in SI.
    period : float or None
        [s] the oscillator's period, for ``sa(T)``.
    rotd : int or None
        50 or 100: the RotD50 or RotD100 of the measure over the two horizontal components (Boore
        2010, `intensity.rotd_peaks`); None: of the motion along the block.
    """

    name: str
    kind: str
    units: str
    long_name: str
    label: str
    display_unit: str
    display_scale: float
    period: float | None = None
    rotd: int | None = None

    def of_pair(self, a1, a2, dt: float) -> float:
        """RotD50 or RotD100 of two orthogonal horizontal components [m/s^2] sampled at ``dt`` [s]."""
        from ..core import intensity  # numba and scipy: where a measure is taken (`risk` takes none)

        measure = "sa" if self.period is not None else self.name.split("_", 1)[1]
        peaks = intensity.rotd_peaks(a1, a2, dt, measure, self.period)
        return float(np.median(peaks) if self.rotd == 50 else np.max(peaks))

    @property
    def of_support(self) -> bool:
        """Whether it is a measure of the motion the block stands on (``pfa``, ``pfv``: the floor's
        with ``ground.floor``), not of the record as read."""
        return self.name in ("pfa", "pfv")

    def of_record(self, acceleration, dt: float, gravity: float, tan_alpha: float) -> float:
        """The measure of a horizontal record [SI] (for ``pfa`` and ``pfv``: of the floor's motion);
        ``gravity`` [m/s^2] and ``tan_alpha`` (the block's b/h) serve ``pga_rocking``."""
        from ..core import intensity

        if self.name in ("pgv", "pfv"):
            return intensity.peak_velocity(acceleration, dt)
        if self.period is not None:
            return intensity.spectral_acceleration(acceleration, dt, self.period)
        peak = intensity.peak_acceleration(acceleration)
        return peak / (gravity * tan_alpha) if self.name == "pga_rocking" else peak

    def axis_label(self) -> str:
        """``PGA [g]``, ``PGA / (g tan α)`` (dimensionless: no unit)."""
        return f"{self.label} [{self.display_unit}]" if self.display_unit else self.label

    def number(self, value: float) -> str:
        """A value [SI] as a number in the display unit, e.g. ``0.62``."""
        return f"{value / self.display_scale:.3g}"

    def show(self, value: float) -> str:
        """A value [SI] in the display unit, e.g. ``0.62 g``."""
        number = self.number(value)
        return f"{number} {self.display_unit}" if self.display_unit else number


_CM_PER_S = 0.01
#: The fixed measures by name; ``sa(T)`` is made by `parse_im`.
INTENSITY_MEASURES = {m.name: m for m in (
    IntensityMeasure("pga", "acceleration", "m/s^2", "peak horizontal ground acceleration", "PGA", "g",
                     STANDARD_GRAVITY),
    IntensityMeasure("pgv", "velocity", "m/s", "peak horizontal ground velocity (baseline-corrected)",
                     "PGV", "cm/s", _CM_PER_S),
    IntensityMeasure("pga_rocking", "dimensionless", "1", "rocking-normalised PGA: PGA / (g tan alpha)",
                     "PGA / (g tan α)", "", 1.0),
    IntensityMeasure("pfa", "acceleration", "m/s^2", "peak horizontal floor acceleration (of the motion the "
                     "block stands on)", "PFA", "g", STANDARD_GRAVITY),
    IntensityMeasure("pfv", "velocity", "m/s", "peak horizontal floor velocity (of the motion the block stands "
                     "on, baseline-corrected)", "PFV", "cm/s", _CM_PER_S),
)}
#: ``sa(T)``; possessive quantifiers keep the match linear (``sa(`` and 20 000 spaces took minutes).
_SA = re.compile(r"^\s*+sa\s*+\((?P<period>[^()]*+)\)\s*+$", re.IGNORECASE)
_IM_CHOICES = ("pga, pgv, pga_rocking, pfa, pfv or sa(T) with a period, e.g. 'sa(0.5s)'; with two horizontal "
               "components also rotd50_ or rotd100_ of pga, pgv, sa(T), e.g. 'rotd50_sa(1s)'")
_ROTD = re.compile(r"^rotd(50|100)_(.*)$")


#: [s] Periods of ``sa(T)``: the range of response spectra (NGA-West2 tabulates 0.01 s to 20 s).
SA_PERIODS = (1e-3, 100.0)


def parse_im(text: str) -> IntensityMeasure:
    """Read ``--im``: ``pga``, ``pgv``, ``pga_rocking`` or ``sa(T)`` (``sa(0.5s)``, ``sa(300 ms)``).

    Raises
    ------
    CaseError
        Naming ``--im``: an unknown measure, a period that is not a positive time, or PGV/PGA
        (scaling a record does not change it).
    """
    name = str(text).strip().lower()
    rotd = _ROTD.match(name)
    if rotd is not None:
        inner = rotd.group(2).strip()
        if inner not in ("pga", "pgv") and _SA.match(inner) is None:
            raise CaseError(f"unknown intensity measure {text!r}: RotD{rotd.group(1)} applies to pga, pgv and "
                            "sa(T), e.g. 'rotd50_sa(1s)'", source="im")
        base = parse_im(inner)
        percent = int(rotd.group(1))
        return replace(base, name=f"rotd{percent}_{base.name}", label=f"RotD{percent} {base.label}",
                       long_name=f"RotD{percent} of the {base.long_name.replace('horizontal record', 'record')} "
                       "over the horizontal directions (two components)", rotd=percent)
    if name in INTENSITY_MEASURES:
        return INTENSITY_MEASURES[name]
    if name.replace(" ", "") in ("pgv_pga", "pgv/pga"):
        raise CaseError("PGV/PGA does not change when a record is scaled, so records cannot be scaled "
                        f"to levels of it (it is reported for each record); choose {_IM_CHOICES}",
                        source="im")
    match = _SA.match(name)
    if match is None:
        raise CaseError(f"unknown intensity measure {text!r}; expected {_IM_CHOICES}", source="im")
    period = parse_quantity(match.group("period"), "time", source="im")
    if not period > 0:
        raise CaseError(f"the period of sa(T) must be a positive time, got {match.group('period')!r}",
                        source="im")
    low, high = SA_PERIODS
    if not low <= period <= high:
        raise CaseError(f"the period of sa(T) must be within {low:g} s ... {high:g} s (a response spectrum's "
                        f"range: below it Sa is the PGA), got {period:g} s", source="im")
    from ..core import intensity

    shown, damping = f"{period:g} s", f"{100 * intensity.DAMPING:g} %"
    return IntensityMeasure(f"sa({shown})", "acceleration", "m/s^2",
                            f"pseudo-spectral acceleration of the horizontal record at T = {shown}, "
                            f"{damping} damping", f"Sa({shown}, {damping})", "g", STANDARD_GRAVITY, period)
