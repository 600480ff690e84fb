"""Attacks on where studies write and wait (issue 43: 1, 7, 8, 12): a name that is a path, links
planted in a shared output folder, shards of one study, a cluster that stops answering."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest
from conftest import REPO, invoke, one_line_error

from rockslide import api
from rockslide.errors import CaseError
from rockslide.io import files

HAZARD = REPO / "rockslide" / "hazard-example-PGA.csv"
posix = pytest.mark.skipif(os.name != "posix", reason="links and flock are POSIX")


def _case(ws):
    (ws / "case.yaml").write_text((REPO / "configs" / "example.yaml").read_text().replace("../records/", ""))


@pytest.mark.parametrize("name", ["../escaped", "/tmp/rockslide-escaped", "a/b", "..", ""])
def test_a_risk_name_is_a_name_not_a_path(ws, name):
    """``risk --name ../escaped`` wrote its result outside ``--out-dir``, exit 0."""
    (ws / "out").mkdir()
    result = invoke("risk", "--median", "0.5g", "--beta", "0.4", "--hazard", HAZARD, "--out-dir", "out",
                    "--name", name)
    one_line_error(result, "--name", "is not a name")
    assert sorted(p.name for p in ws.rglob("*.risk.*")) == []
    assert not os.path.exists("/tmp/rockslide-escaped.risk.h5")


@posix
def test_a_lock_file_planted_as_a_link_is_refused(ws, tmp_path_factory):
    """A link at the study's lock name disabled the lock; it is now one line naming it."""
    _case(ws)
    (ws / "out").mkdir()
    elsewhere = tmp_path_factory.mktemp("elsewhere") / "target"
    elsewhere.write_text("")
    os.symlink(elsewhere, ws / "out" / ".example.sweep.h5.lock")
    one_line_error(invoke("sweep", "case.yaml", "--mu", "0.3,0.5", "--out-dir", "out", "--no-plot"),
                   ".example.sweep.h5.lock", "is a link")
    assert not (ws / "out" / "example.sweep.h5").exists()


@posix
def test_a_chunk_folder_planted_as_a_link_receives_nothing(ws, tmp_path_factory):
    """A study's chunk folder planted as a link to another folder received the study's files there."""
    _case(ws)
    (ws / "out").mkdir()
    elsewhere = tmp_path_factory.mktemp("elsewhere")
    os.symlink(elsewhere, ws / "out" / ".example.sweep.chunks")
    one_line_error(invoke("sweep", "case.yaml", "--mu", "0.3,0.5", "--out-dir", "out", "--no-plot"),
                   ".example.sweep.chunks", "is a link")
    assert list(elsewhere.iterdir()) == []


@posix
def test_the_shards_of_one_study_do_not_wait_for_each_other(ws, monkeypatch):
    """``--shard I/N`` took the study's lock for the whole run: N shards ran one after the other.
    Deterministic: another shard holds the lock (shared, as a running shard does) while this one
    starts; waiting for it is an error here (the note a waiter prints is replaced by a failure)."""
    _case(ws)
    (ws / "out").mkdir()

    def waits(what):
        raise AssertionError(f"the shard waited: {what}")

    monkeypatch.setattr(files, "_say_waiting", waits)
    with files.exclusive(ws / "out" / ".example.sweep.h5.lock", waiting_for="a test", shared=True):
        result = invoke("sweep", "case.yaml", "--mu", "0.3,0.5", "--out-dir", "out", "--no-plot", "--shard", "1/2")
    assert result.exit_code == 0, result.output
    assert "shard 1/2 computed" in result.stdout


@posix
def test_a_study_that_collects_waits_for_a_running_shard(ws, monkeypatch):
    """The same lock held by a shard: a sweep without --shard (which collects and removes the chunk
    folder) waits for it; made deterministic by failing at the note a waiter prints."""
    _case(ws)
    (ws / "out").mkdir()

    class Waited(Exception):
        pass

    def waits(what):
        raise Waited(what)

    monkeypatch.setattr(files, "_say_waiting", waits)
    outputs = api.OutputSet(ws / "out", "example", "sweep", plot=False)
    with files.exclusive(ws / "out" / ".example.sweep.h5.lock", waiting_for="a test", shared=True), \
            pytest.raises(Waited):
        api.sweep_study(ws / "case.yaml", [("mu", "0.3,0.5")], outputs=outputs)
    assert not (ws / "out" / "example.sweep.h5").exists()


@pytest.mark.parametrize("value", ["nan", "inf", "-1", "1e9"])
def test_a_wait_for_workers_that_is_not_a_time_is_refused_first(ws, value):
    """``--wait-workers nan`` waited 60 s and more."""
    _case(ws)
    started = time.monotonic()
    one_line_error(invoke("sweep", "case.yaml", "--mu", "0.3", "--scheduler", "tcp://127.0.0.1:1",
                          "--wait-workers", value), "--wait-workers")
    assert time.monotonic() - started < 10


class _Pending:
    status = "pending"


class _Client:
    status = "running"

    def nthreads(self):
        return {"tcp://worker": 1}            # a worker the scheduler still counts, frozen


def test_a_cluster_that_finishes_nothing_is_given_up_with_one_line(tmp_path, monkeypatch):
    """A study whose only worker was frozen (SIGSTOP) waited for ever; now, after ``stall`` seconds
    without a finished chunk, one line saying what it waited for and what is kept."""
    from rockslide.engine import cluster
    from rockslide.engine.chunks import ChunkStore

    monkeypatch.setattr(cluster, "STALL_NOTE", 0.05)
    said = []
    store = ChunkStore(tmp_path / "chunks", "0" * 64)
    futures = {_Pending(): (0, np.arange(3))}
    started = time.monotonic()
    with pytest.raises(CaseError, match="no chunk finished on the cluster") as caught:
        cluster._collect_futures(_Client(), futures, store, "tcp://sched:8786", None, stall=0.5, say=said.append)
    assert 0.5 <= time.monotonic() - started < 10
    assert caught.value.source == "scheduler" and "resumes" in caught.value.message
    assert len(said) == 1 and "waiting for 1 chunks" in said[0]


def test_a_hazard_curve_of_millions_of_levels_is_refused_while_read(ws):
    """``risk`` with 2 million hazard levels ran past 300 s; it is now one line naming the line where
    the curve passes `hazard.MAX_LEVELS`, after reading a bounded share of the file."""
    from rockslide.io import hazard

    rows = "\n".join(f"{0.001 * (1 + i * 1e-4):.9g},{1e-2 / (1 + i):.9g}" for i in range(hazard.MAX_LEVELS + 5))
    (ws / "big.csv").write_text("PGA [g],annual rate\n" + rows + "\n")
    started = time.monotonic()
    one_line_error(invoke("risk", "--median", "0.5g", "--beta", "0.4", "--hazard", "big.csv", "--no-plot"),
                   "big.csv", f"line {hazard.MAX_LEVELS + 2}", f"more than {hazard.MAX_LEVELS} levels in one table")
    assert time.monotonic() - started < 10


def test_a_suite_that_lists_a_record_twice_is_refused(ws):
    """A suite listing one record hundreds of times ran for minutes, then out of memory; one record
    listed twice is now one line naming both entries, before any record is read."""
    _case(ws)
    entries = "\n".join(f"  - {{name: r{i}, horizontal: synthetic_kt_h.at2}}" for i in range(300))
    (ws / "suite.yaml").write_text(f"records:\n{entries}\n")
    one_line_error(invoke("fragility", "case.yaml", "--suite", "suite.yaml", "--levels", "0.2g", "--no-plot"),
                   "suite.yaml", "records[1] (r1) is records[0] (r0) again")
