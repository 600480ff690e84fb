"""The study kinds, registered once: each kind's file format, the name its files carry, and the
figures of its files read back. What dispatches on a kind (reading a file back, drawing it,
overlaying several, describing it) looks it up here instead of testing kinds one by one.

Adding an analysis is an engine plan, its statistics and an entry here.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass


@dataclass(frozen=True)
class StudyKind:
    """One kind of result.

    Attributes
    ----------
    name : str
        ``"run"``, ``"sweep"``, ``"fragility"`` or ``"risk"``.
    format : str
        The ``format`` attribute of its files (`io.results`; a test keeps them equal).
    what : str
        How a message names its files.
    module : str
        The analyses module that draws its files read back (``stored_figure``, ``overlay_figure``);
        empty for a run (`plots.response_figure`).
    overlays : bool
        Whether several of its files can be drawn on one figure.
    """

    name: str
    format: str
    what: str
    module: str = ""
    overlays: bool = True

    def stored_figure(self, stored, *, size=None):
        """The figure of one of its files read back (`io.results.read_dataset`)."""
        module = importlib.import_module(self.module)
        if self.name == "risk":                  # drawn from its dataset's three parts
            return module.stored_figure(stored.coords, stored.variables, stored.attrs, size=size)
        return module.stored_figure(stored, size=size)

    def overlay_figure(self, stored_files, names, *, size=None):
        """The figure of several of its files read back."""
        return importlib.import_module(self.module).overlay_figure(stored_files, names, size=size)


KINDS = {kind.name: kind for kind in (
    StudyKind("run", "rockslide-result", "result file"),
    StudyKind("sweep", "rockslide-sweep", "sweep file", "rockslide.analyses.sweep"),
    StudyKind("fragility", "rockslide-fragility", "fragility file", "rockslide.analyses.fragility"),
    StudyKind("risk", "rockslide-risk", "risk file", "rockslide.analyses.risk", overlays=False),
)}


def of_format(format: str | None) -> StudyKind:
    """The kind of a file of ``format`` (`io.results.file_format`); a run's when unknown (its reader
    then says what the file is not)."""
    return next((kind for kind in KINDS.values() if kind.format == format), KINDS["run"])
