"""The Python API with arguments of the wrong type or size (issue 43.9): rockslide's own error,
naming the argument, before any work; never a raw Python error, never gigabytes first."""

from __future__ import annotations

import pytest
from conftest import REPO

import rockslide
from rockslide.errors import RockslideError

HAZARD = str(REPO / "rockslide" / "hazard-example-PGA.csv")


def _loop():
    loop = {}
    loop["a"] = loop
    return loop


CALLS = {
    "load_case(None)": ("case", lambda c: rockslide.load_case(None)),
    "load_case(list)": ("case", lambda c: rockslide.load_case([1, 2])),
    "load_case(int)": ("case", lambda c: rockslide.load_case(3)),
    "load_case(a mapping that holds itself)": ("case", lambda c: rockslide.load_case(_loop())),
    "run(None)": ("case", lambda c: rockslide.run(None)),
    "run(records_dir=3)": ("records_dir", lambda c: rockslide.run(c, records_dir=3)),
    "run(pga=list)": ("pga", lambda c: rockslide.run(c, pga=[1, 2])),
    "run(seed=text)": ("seed", lambda c: rockslide.run(c, seed="abc")),
    "sweep(workers=text)": ("workers", lambda c: rockslide.sweep(c, mu="0.3", workers="many")),
    "sweep(chunk_size=text)": ("chunk_size", lambda c: rockslide.sweep(c, mu="0.3", chunk_size="a")),
    "sweep(mu=3)": ("mu", lambda c: rockslide.sweep(c, mu=3)),
    "sweep(mu=[None])": ("mu", lambda c: rockslide.sweep(c, mu=[None])),
    "sweep(mu=range(10**8))": ("mu", lambda c: rockslide.sweep(c, mu=range(10**8))),
    "sweep(mu=an endless generator)": ("mu", lambda c: rockslide.sweep(c, mu=(0.3 for _ in iter(int, 1)))),
    "sweep(progress=3)": ("progress", lambda c: rockslide.sweep(c, mu="0.3", progress=3)),
    "sweep(store=text)": ("store", lambda c: rockslide.sweep(c, mu="0.3", store="x")),
    "sweep(wait_workers=text)": ("wait_workers", lambda c: rockslide.sweep(c, mu="0.3", wait_workers="x")),
    "sweep(mu_kinetic_ratio=text)": ("mu_kinetic_ratio", lambda c: rockslide.sweep(c, mu="0.3", mu_kinetic_ratio="x")),
    "ensemble(seed=text)": ("seed", lambda c: rockslide.ensemble(c, 5, seed="abc")),
    "ensemble(n=2.5)": ("n", lambda c: rockslide.ensemble(c, 2.5)),
    "risk(hazard=3)": ("hazard", lambda c: rockslide.risk(median="0.5g", beta=0.4, hazard=3)),
    "risk(hazard={name: 3})": ("hazard['a']", lambda c: rockslide.risk(median="0.5g", beta=0.4, hazard={"a": 3})),
    "risk(confidence=text)": ("confidence", lambda c: rockslide.risk(median="0.5g", beta=0.4, hazard=HAZARD,
                                                                     confidence="x")),
    "export_pelicun(a run file)": (None, lambda c: rockslide.export_pelicun(c, "X.1", "p.csv")),
    "read_result(3)": ("path", lambda c: rockslide.read_result(3)),
    "plot_results(3)": ("results", lambda c: rockslide.plot_results(3)),
    "plot_results([None])": ("results", lambda c: rockslide.plot_results([None])),
    "fragility(suite=3)": ("suite", lambda c: rockslide.fragility(c, 3, levels="0.1g")),
    "fragility(levels=3)": ("levels", lambda c: rockslide.fragility(c, "s.yaml", levels=3)),
    "fragility(resamples=text)": ("resamples", lambda c: rockslide.fragility(c, "s.yaml", levels="0.1g",
                                                                             resamples="x")),
    "case_with(case, 3)": ("changes", lambda c: rockslide.case_with(c, 3)),
}


@pytest.mark.parametrize("name", CALLS)
def test_a_wrong_argument_is_one_error_naming_it(example, name):
    argument, call = CALLS[name]
    with pytest.raises(RockslideError) as caught:
        call(example)
    if argument is not None:
        assert caught.value.source == argument, str(caught.value)
    assert "--" not in str(caught.value)
