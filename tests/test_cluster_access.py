"""Clusters as people run them: a scheduler secured with TLS (dask's own options and configuration),
the scheduler found before any planning, a distributed.Client or a cluster object from the Python
API, and dask-jobqueue's SLURMCluster with stand-ins for sbatch and scancel.

Certificates are made here with the ``openssl`` command (a CA, a certificate it signs, and a second
CA with its own certificate: the wrong one). Every result computed on a cluster is compared bit for
bit with the same study on local threads. Synchronisation is on what processes print and on
conditions with generous bounds, never on sleeps that could be too short.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import CLUSTER_AXES as AXES
from conftest import CLUSTER_CHUNKS as CHUNKS
from conftest import REPO, dask_processes, invoke, one_line_error, sweep_args, variables_equal

import rockslide
from rockslide.errors import CaseError

distributed = pytest.importorskip("distributed")
EXAMPLE = REPO / "configs" / "example.yaml"
RECORDS = REPO / "records"
posix = pytest.mark.skipif(os.name != "posix", reason="POSIX processes and signals")

#: The API's form of `test_cluster.AXES` and `CHUNKS` (4 x 6 = 24 cases in 5 chunks).
API_AXES = {"mu": "0.4:0.7:0.1", "pga": "400gal:900gal:100gal", "chunk_size": 5}
#: No TLS file from the environment's dask configuration (a developer's ~/.config/dask may set them).
NO_TLS_CONFIG = {"distributed.comm.tls.ca-file": None, "distributed.comm.tls.client.cert": None,
                 "distributed.comm.tls.client.key": None}


def _openssl(*args: str, cwd: Path) -> None:
    done = subprocess.run(["openssl", *args], cwd=cwd, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr


def make_certificates(folder: Path, name: str) -> tuple[Path, Path, Path]:
    """A CA ``NAME-ca.pem`` and a certificate ``NAME.pem`` (key ``NAME.key``) it signs, made with
    the openssl command; returns ``(ca, certificate, key)``."""
    folder.mkdir(parents=True, exist_ok=True)
    _openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", f"{name}-ca.key", "-out", f"{name}-ca.pem",
             "-days", "2", "-subj", f"/CN={name}-ca", cwd=folder)
    _openssl("req", "-newkey", "rsa:2048", "-nodes", "-keyout", f"{name}.key", "-out", f"{name}.csr",
             "-subj", f"/CN={name}", cwd=folder)
    _openssl("x509", "-req", "-in", f"{name}.csr", "-CA", f"{name}-ca.pem", "-CAkey", f"{name}-ca.key",
             "-CAcreateserial", "-out", f"{name}.pem", "-days", "2", cwd=folder)
    return folder / f"{name}-ca.pem", folder / f"{name}.pem", folder / f"{name}.key"


@pytest.fixture(scope="module")
def certificates(tmp_path_factory):
    """``(good, other)``: the cluster's ``(ca, cert, key)`` and those of another CA."""
    if shutil.which("openssl") is None:
        pytest.skip("needs the openssl command to make test certificates (apt install openssl)")
    folder = tmp_path_factory.mktemp("tls")
    return make_certificates(folder, "cluster"), make_certificates(folder, "other")


def tls_options(ca: Path, cert: Path, key: Path) -> list:
    """dask's (and rockslide's) command-line options for these files."""
    return ["--tls-ca-file", ca, "--tls-cert", cert, "--tls-key", key]


@pytest.fixture
def tls_scheduler(certificates):
    """A TLS-only dask scheduler in its own process (`conftest.dask_processes`), its workers started
    with the same certificates."""
    good, _ = certificates
    with dask_processes(["--protocol", "tls", *tls_options(*good)], tls_options(*good)) as cluster:
        assert cluster.address.startswith("tls://127.0.0.1:")
        yield cluster


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory):
    """`test_cluster`'s sweep on local threads: the reference of every cluster run here."""
    out = tmp_path_factory.mktemp("local")
    result = invoke(*sweep_args(out, *AXES, extra=["--no-plot", *CHUNKS]))
    assert result.exit_code == 0, result.output
    return out / "example.sweep.h5"


def closed_port() -> int:
    """A loopback port nothing listens on (one the system just gave and took back)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def datasets_equal(a, b) -> None:
    """Two API sweeps hold the same grid, exactly the same values (NaN where NaN), and the same
    attributes (`xarray.testing.assert_identical` compares exactly, no tolerance)."""
    import xarray

    xarray.testing.assert_identical(a, b)


# --------------------------------------------------------------------------------------------------
# TLS: the files checked before anything else, then a real TLS scheduler
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("where, extra, parts", [
    ("tls://127.0.0.1:1", [], ["--scheduler", "is a TLS scheduler", "--tls-ca-file", "--tls-cert",
                               "distributed.comm.tls.ca-file"]),
    ("tls://127.0.0.1:1", ["--tls-ca-file", "missing-ca.pem", "--tls-cert", "cert"],
     ["--tls-ca-file: cannot read missing-ca.pem", "No such file"]),
    ("tls://127.0.0.1:1", ["--tls-ca-file", "ca", "--tls-cert", "cert", "--tls-key", "missing.key"],
     ["--tls-key: cannot read missing.key"]),
    ("tls://127.0.0.1:1", ["--tls-ca-file", "key", "--tls-cert", "cert", "--tls-key", "key"],
     ["--tls-ca-file:", "is not a CA certificate in PEM format"]),
    ("tls://127.0.0.1:1", ["--tls-ca-file", "ca", "--tls-cert", "cert", "--tls-key", "other key"],
     ["--tls-cert: cannot load this client's certificate", "--tls-key"]),
    ("tcp://127.0.0.1:1", ["--tls-ca-file", "ca", "--tls-cert", "cert", "--tls-key", "key"],
     ["--tls-ca-file: is for a TLS scheduler", "tcp://127.0.0.1:1 is plain TCP", "tls://HOST:PORT"]),
    (None, ["--tls-cert", "cert"], ["--tls-cert: is for a TLS dask scheduler", "scheduler tls://"]),
], ids=["no-certificate", "missing-ca", "missing-key", "key-as-ca", "key-of-another", "tls-files-with-tcp",
        "tls-files-without-scheduler"])
def test_bad_tls_input_is_one_line_before_any_connection(tmp_path, certificates, monkeypatch, where, extra,
                                                         parts):
    """Port 1 of loopback has no scheduler: each of these is said before any connection is tried."""
    import dask

    (ca, cert, key), (_, _, other_key) = certificates
    files = {"ca": ca, "cert": cert, "key": key, "other key": other_key}
    monkeypatch.chdir(tmp_path)
    with dask.config.set(NO_TLS_CONFIG):
        result = invoke(*sweep_args(tmp_path, "--mu", "0.5", extra=[*(["--scheduler", where] if where else []),
                                                                    *[files.get(e, e) for e in extra]]))
    one_line_error(result, *parts)


def test_tls_files_from_daskconfig_are_named_by_their_key(tmp_path, certificates):
    """Without the options, dask's configuration gives the files (as distributed.Security reads it,
    also from DASK_DISTRIBUTED__COMM__TLS__* variables); an error names the key that gave the file."""
    import dask

    ca, cert, _ = certificates[0]
    with dask.config.set({"distributed.comm.tls.ca-file": str(ca), "distributed.comm.tls.client.cert": str(cert),
                          "distributed.comm.tls.client.key": str(tmp_path / "gone.key")}):
        result = invoke(*sweep_args(tmp_path, "--mu", "0.5", extra=["--scheduler", "tls://127.0.0.1:1"]))
    one_line_error(result, "dask's configuration distributed.comm.tls.client.key: cannot read", "gone.key")


@posix
@pytest.mark.slow
@pytest.mark.parametrize("given", ["options", "dask-config"])
def test_a_sweep_over_tls_equals_local_threads(tls_scheduler, certificates, local_sweep, tmp_path, given):
    """A TLS-only scheduler and worker: the sweep over tls:// (certificates given as options, or
    by dask's configuration alone) publishes a result equal bit for bit to local threads', and
    says nothing on stderr."""
    import dask

    tls_scheduler.start_worker()
    good, _ = certificates
    config = dict(zip(NO_TLS_CONFIG, map(str, good), strict=True))
    options = tls_options(*good) if given == "options" else []
    with dask.config.set(NO_TLS_CONFIG if given == "options" else config):
        result = invoke(*sweep_args(tmp_path, *AXES, extra=["--no-plot", *CHUNKS, "--scheduler",
                                                             tls_scheduler.address, *options]))
    assert result.exit_code == 0, (result.output, result.exception)
    assert f"on the dask scheduler {tls_scheduler.address}" in result.stdout and result.stderr == ""
    variables_equal(local_sweep, tmp_path / "example.sweep.h5")


@posix
@pytest.mark.parametrize("who, words", [
    ("ca", "the scheduler's certificate was not accepted: it is not signed by the CA certificate given"),
    ("cert", "this client's certificate was not accepted by the scheduler"),
], ids=["wrong-ca", "client-certificate-of-another-ca"])
def test_a_certificate_of_another_ca_is_one_line(tls_scheduler, certificates, tmp_path, who, words):
    """The wrong CA (the scheduler's certificate cannot be verified) or a client certificate of
    another CA (the scheduler hangs up during the handshake): one line, exit 2, before planning."""
    good, other = certificates
    files = (other[0], *good[1:]) if who == "ca" else (good[0], *other[1:])
    result = invoke(*sweep_args(tmp_path, "--mu", "0.5", extra=["--scheduler", tls_scheduler.address,
                                                                 *tls_options(*files)]))
    one_line_error(result, f"--scheduler: cannot connect to the dask scheduler at {tls_scheduler.address}", words)
    assert result.stdout == ""


@posix
def test_a_tls_scheduler_given_as_tcp_says_so(tls_scheduler, tmp_path):
    result = invoke(*sweep_args(tmp_path, "--mu", "0.5",
                                extra=["--scheduler", tls_scheduler.address.replace("tls://", "tcp://")]))
    one_line_error(result, "the connection was reset (a TLS scheduler? give its tls:// address")


# --------------------------------------------------------------------------------------------------
# the scheduler found before any planning
# --------------------------------------------------------------------------------------------------

#: A grid of 2 x 10^6 points: above the cap of one sweep, and minutes of planning below it.
HUGE = ("--mu", "0.001:1:0.001", "--pga", "1gal:2000gal:1gal")


def test_an_unreachable_scheduler_is_said_before_planning(tmp_path):
    """A closed port: the one line is about the scheduler, not about the grid planning would have
    refused (or spent minutes on), and nothing of the planning is printed."""
    address = f"tcp://127.0.0.1:{closed_port()}"
    result = invoke(*sweep_args(tmp_path, *HUGE, extra=["--scheduler", address]))
    one_line_error(result, f"--scheduler: cannot connect to the dask scheduler at {address}", "refused")
    assert result.stdout == ""
    with pytest.raises(CaseError, match=f"cannot connect to the dask scheduler at {address}"):
        rockslide.sweep(EXAMPLE, records_dir=RECORDS, scheduler=address, mu=HUGE[1], pga=HUGE[3])


def test_fragility_finds_its_tls_scheduler_first(certificates, tmp_path):
    """`rockslide fragility` takes the same options: HOST:PORT with TLS files is tls://, and a
    closed port is said before the suite is read."""
    port = closed_port()
    result = invoke("fragility", EXAMPLE, "--suite", tmp_path / "not-read.yaml", "--levels", "0.1g",
                    "--records-dir", RECORDS, "--out-dir", tmp_path, "--scheduler", f"127.0.0.1:{port}",
                    *tls_options(*certificates[0]))
    one_line_error(result, f"--scheduler: cannot connect to the dask scheduler at tls://127.0.0.1:{port}", "refused")


@posix
@pytest.mark.slow
def test_dasks_table_of_mismatched_versions_never_reaches_the_terminal(tls_scheduler, certificates, tmp_path):
    """A worker that reports another toolz (dask prints a table of mismatched versions for it; the
    worker's rockslide is the same, so the sweep runs): a sweep over TLS in its own process says
    nothing on stderr and its printout holds no table."""
    preload = tmp_path / "other_toolz.py"
    # (dask may load a preload file twice: patch once)
    preload.write_text("import distributed.versions as v\n"
                       "_info = v.__dict__.setdefault('_unpatched_info', v.get_package_info)\n"
                       "v.get_package_info = lambda packages: {**_info(packages), 'toolz': '0.0.1'}\n")
    tls_scheduler.start_worker(preload)
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    done = subprocess.run([sys.executable, "-m", "rockslide",
                           *map(str, sweep_args(tmp_path, "--mu", "0.5", extra=[
                               "--no-plot", "--scheduler", tls_scheduler.address, "--wait-workers", "120",
                               *tls_options(*certificates[0])]))],
                          env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0 and done.stderr == "", (done.stdout, done.stderr)
    assert "Mismatched versions" not in done.stdout and "toolz" not in done.stdout


# --------------------------------------------------------------------------------------------------
# the Python API: a distributed.Client, a cluster object
# --------------------------------------------------------------------------------------------------


@posix
@pytest.mark.slow
def test_a_client_and_a_cluster_object_equal_local_threads(certificates, monkeypatch):
    """A LocalCluster of one worker process secured with TLS: given as a cluster object, rockslide
    connects with its ``security``; given as a distributed.Client, it uses the client as is and
    leaves it open. Both give the local threads' dataset exactly."""
    monkeypatch.setenv("PYTHONPATH", str(REPO))          # the worker processes import this rockslide
    ca, cert, key = (str(p) for p in certificates[0])
    security = distributed.Security(require_encryption=True, tls_ca_file=ca, tls_client_cert=cert,
                                    tls_client_key=key, tls_scheduler_cert=cert, tls_scheduler_key=key,
                                    tls_worker_cert=cert, tls_worker_key=key)
    local = rockslide.sweep(EXAMPLE, records_dir=RECORDS, **API_AXES)
    with distributed.LocalCluster(processes=True, n_workers=1, threads_per_worker=1, host="127.0.0.1",
                                  protocol="tls://", security=security, dashboard_address=":0") as cluster:
        assert cluster.scheduler_address.startswith("tls://")
        datasets_equal(local, rockslide.sweep(EXAMPLE, records_dir=RECORDS, scheduler=cluster, **API_AXES))
        with distributed.Client(cluster, set_as_default=False) as client:
            datasets_equal(local, rockslide.sweep(EXAMPLE, records_dir=RECORDS, scheduler=client, **API_AXES))
            assert client.status == "running"                  # not closed by rockslide


def test_a_closed_client_and_other_objects_are_refused():
    client = distributed.Client(distributed.LocalCluster(processes=False, n_workers=0, dashboard_address=":0"),
                                set_as_default=False)
    cluster = client.cluster
    client.close()
    cluster.close()
    with pytest.raises(CaseError, match="the distributed.Client given is closed"):
        rockslide.sweep(EXAMPLE, records_dir=RECORDS, scheduler=client, mu="0.5")
    with pytest.raises(CaseError, match="expected an address .* got int"):
        rockslide.sweep(EXAMPLE, records_dir=RECORDS, scheduler=8786, mu="0.5")


# --------------------------------------------------------------------------------------------------
# dask-jobqueue: the documented recipe, with stand-ins for SLURM's commands
# --------------------------------------------------------------------------------------------------

#: ``sbatch SCRIPT``: runs the job script in the background, in a session of its own (so that
#: ``scancel`` ends the worker and its nanny together), and answers as SLURM does.
FAKE_SBATCH = """#!/bin/sh
dir=$(dirname "$0")
n=$(ls "$dir"/jobs | wc -l); n=$((n + 1))
cp "$1" "$dir/jobs/$n.sh"
setsid sh "$dir/jobs/$n.sh" > "$dir/logs/$n.log" 2>&1 < /dev/null &
echo $! > "$dir/pids/$n"
echo "Submitted batch job $n"
"""
FAKE_SCANCEL = """#!/bin/sh
dir=$(dirname "$0")
for job in "$@"; do kill -TERM -- -$(cat "$dir/pids/$job") 2>/dev/null; done
exit 0
"""
FAKE_SQUEUE = """#!/bin/sh
echo "JOBID PARTITION NAME USER ST TIME NODES NODELIST(REASON)"
"""


@pytest.fixture
def fake_slurm(tmp_path, monkeypatch):
    """A folder of stand-ins for sbatch, scancel and squeue, first on PATH; yields it, and ends every
    job's process group still alive at the end."""
    folder = tmp_path / "slurm"
    for sub in ("jobs", "logs", "pids"):
        (folder / sub).mkdir(parents=True)
    for name, text in (("sbatch", FAKE_SBATCH), ("scancel", FAKE_SCANCEL), ("squeue", FAKE_SQUEUE)):
        (folder / name).write_text(text)
        (folder / name).chmod(stat.S_IRWXU)
    monkeypatch.setenv("PATH", f"{folder}{os.pathsep}{os.environ['PATH']}")
    try:
        yield folder
    finally:
        for pid_file in (folder / "pids").iterdir():
            try:
                os.killpg(int(pid_file.read_text()), signal.SIGKILL)
            except ProcessLookupError:
                pass


def _group_alive(pid: int) -> bool:
    try:
        os.killpg(pid, 0)
    except ProcessLookupError:
        return False
    return True


@posix
@pytest.mark.slow
def test_dask_jobqueue_recipe_with_late_workers(fake_slurm, local_sweep, tmp_path):
    """docs/clusters.md's recipe: a SLURMCluster scaled to one job after the sweep, started with
    its scheduler address, says it waits (the job starts late); the job's worker joins and the
    sweep publishes the local result. Then the API with the cluster object itself; closing the
    cluster cancels the job and its worker processes end."""
    jobqueue = pytest.importorskip("dask_jobqueue")
    with jobqueue.SLURMCluster(cores=1, processes=1, memory="1GB", walltime="00:10:00",
                               scheduler_options={"host": "127.0.0.1", "dashboard_address": ":0"},
                               interface=None, job_script_prologue=[f"export PYTHONPATH={REPO}"],
                               worker_extra_args=["--host", "127.0.0.1"]) as cluster:
        env = {**os.environ, "PYTHONPATH": str(REPO)}
        proc = subprocess.Popen([sys.executable, "-m", "rockslide",
                                 *map(str, sweep_args(tmp_path, *AXES, extra=[
                                     "--no-plot", *CHUNKS, "--scheduler", cluster.scheduler_address,
                                     "--wait-workers", "600"]))],
                                env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            for line in proc.stdout:                  # synchronise on the sweep saying it waits
                if "waiting for a first dask worker" in line:
                    break
            else:
                pytest.fail(f"the sweep did not wait: {proc.communicate()}")
            cluster.scale(jobs=1)
            out, err = proc.communicate(timeout=600)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        assert proc.returncode == 0 and err == "", (out, err)
        variables_equal(local_sweep, tmp_path / "example.sweep.h5")
        assert (fake_slurm / "jobs" / "1.sh").read_text().count("#SBATCH") >= 3      # a job script, submitted
        local = rockslide.sweep(EXAMPLE, records_dir=RECORDS, **API_AXES)
        datasets_equal(local, rockslide.sweep(EXAMPLE, records_dir=RECORDS, scheduler=cluster, wait_workers=600,
                                              **API_AXES))
    job = int((fake_slurm / "pids" / "1").read_text())
    deadline = time.monotonic() + 60
    while _group_alive(job):                          # scancel ended the job's processes
        assert time.monotonic() < deadline, "the job's worker outlived the cluster"
        time.sleep(0.05)
