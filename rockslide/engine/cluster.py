"""A plan's chunks on a dask.distributed cluster: the scheduler found and asked who it is (its
address, a ``tls://`` one with dask's TLS options, a `distributed.Client` or a cluster object),
its workers checked against this client's rockslide, one task per chunk (`compute_chunk`) on the
plan's arrays sent once, each chunk stored as it arrives (`_collect_futures`), and every way a
cluster fails said in one line: unreachable, no worker in time, workers of another version, lost,
or stalled without progress (`STALL_SECONDS`)."""

from __future__ import annotations

import contextlib
import functools
import time
import warnings
from dataclasses import dataclass

import numpy as np

from .. import interrupts
from ..errors import CaseError, exception_text
from .chunks import ChunkStore
from .plan import Plan


def compute_chunk(inputs, chunk: int, n_chunks: int, identity: dict | None = None) -> np.ndarray:
    """`batch.compute` of chunk ``chunk`` (cases ``chunk, chunk + n_chunks, ...``,
    `Plan.chunk_indices`) from the whole plan's ``inputs`` (`_plan_inputs`): a dask task, run where
    the inputs were sent once. ``identity``: the client's `local_identity`; a worker whose own
    differs (one that joined after `check_workers_match`) refuses the task."""
    if identity is not None and _own_identity() != identity:
        mine = _own_identity()
        raise RuntimeError(f"this worker runs rockslide {mine['rockslide']} (core {mine['core'][:12]}, numba "
                           f"{mine['numba']}), the client {identity['rockslide']} (core {identity['core'][:12]}, "
                           f"numba {identity['numba']}): its results would differ; install the same version")
    params, states, rows, base, first, count, kh, kv = inputs
    cases = slice(chunk, None, n_chunks)
    own = cases if rows is None else rows[cases]
    from ..core import batch

    return batch.compute(params[own], states[own], base, first[cases], count[cases], kh[cases], kv[cases])


def _plan_inputs(plan: Plan) -> list:
    """What `compute_chunk` needs of the whole plan, as stored (distinct rows and ``rows``: a
    10^6-point sweep sends some 50 MB to each worker, not 450)."""
    return [plan.params, plan.states, plan.rows, plan.base, plan.first, plan.count, plan.factor_h, plan.factor_v]


#: [s] for the connection to a dask scheduler, and for a lost one to come back.
SCHEDULER_TIMEOUT = 10.0


#: [s] How long ``--scheduler`` waits for a first worker by default (``--wait-workers``): on SLURM
#: or Kubernetes the scheduler starts first and the workers join when their jobs start.
WAIT_FOR_WORKERS = 120.0
#: [s] The longest wait for a first worker that may be asked for (a day).
MAX_WAIT_WORKERS = 86400.0


def compute_dask(plan, store, chunks, scheduler, progress, wait_workers, say, stall: float | None = None):
    """One task per chunk on the cluster (`batch.compute`, serial in the task); each chunk is
    stored as its result arrives. One bounded connection attempt (`identify_scheduler`), a bounded
    wait for the first worker, every worker's rockslide checked against this one's
    (`check_workers_match`), the cluster's log messages kept off the terminal, Ctrl-C checked
    while waiting. ``scheduler``: an address, or a `Scheduler` (`find_scheduler`); a client the
    caller gave is used as is and left open."""
    try:
        import distributed
    except ImportError:  # pragma: no cover - a declared dependency
        raise CaseError("needs dask.distributed (pip install 'dask[distributed]')",
                        source="scheduler") from None
    with _quiet_dask():
        target = scheduler if isinstance(scheduler, Scheduler) else find_scheduler(scheduler, identify=False)
        address = target.address
        if target.client is not None:
            client = target.client
        else:
            # again: planning may have taken long since `check_where` found it
            identify_scheduler(address, security=target.security)
            try:
                client = distributed.Client(address, security=target.security, timeout=f"{SCHEDULER_TIMEOUT:g}s",
                                            set_as_default=False)
            except (OSError, TimeoutError, ValueError) as exc:
                raise CaseError(f"cannot connect to the dask scheduler at {address}: {exception_text(exc)}",
                                source="scheduler") from None
        futures = {}
        try:
            _wait_for_workers(client, address, wait_workers, say)
            identity = local_identity()
            identities = client.run(worker_identity, identity)
            check_workers_match(identities, identity, address)
            note = cold_workers_note(identities)
            if note:
                say(note)
            # the plan's arrays are sent once to every worker; a task names its chunk only, so that
            # neither the scheduler's memory nor the client's traffic grows with the tasks
            shared = client.scatter(_plan_inputs(plan), broadcast=True)
            for chunk in chunks:
                future = client.submit(compute_chunk, shared, chunk, plan.n_chunks, identity, pure=False)
                futures[future] = (chunk, plan.chunk_indices(chunk))
            _collect_futures(client, futures, store, address, progress, stall=stall or STALL_SECONDS, say=say)
        finally:
            with contextlib.suppress(Exception):
                if futures:
                    client.cancel(list(futures))
            if client is not target.client:
                with contextlib.suppress(Exception):
                    client.close(timeout=2)


#: [s] A study on a cluster gives up when no chunk has finished for this long, or for
#: `STALL_FACTOR` times the longest a chunk could take on one thread (`work_estimate`), whichever is
#: longer: a worker that stopped answering (frozen, its machine gone to sleep) otherwise keeps the
#: scheduler waiting for ever. It says what it waits for after `STALL_NOTE` seconds.
STALL_SECONDS = 600.0
STALL_FACTOR = 3.0
STALL_NOTE = 60.0


def _collect_futures(client, futures: dict, store: ChunkStore, address: str, progress, *,
                     stall: float = STALL_SECONDS, say=None) -> None:
    """Store each chunk as its task finishes; Ctrl-C and a lost scheduler are noticed within a
    fraction of a second and `SCHEDULER_TIMEOUT` respectively; ``stall`` seconds without a chunk
    finished is one line (`STALL_SECONDS`), said first after `STALL_NOTE` seconds."""

    lost_since = None
    no_workers_since = None
    checked = last_done = time.monotonic()
    noted = False
    while futures:
        interrupts.check()
        waited = time.monotonic() - last_done
        if waited > stall:
            raise CaseError(f"no chunk finished on the cluster at {address} for {waited:.0f} s ({len(futures)} "
                            f"waiting; a worker stopped answering?); {store.count()} finished chunks are kept in "
                            f"{store.folder} and the same command resumes from them", source="scheduler")
        if waited > STALL_NOTE and not noted and say is not None:
            say(f"  waiting for {len(futures)} chunks on {address}: none finished for {STALL_NOTE:.0f} s (giving up "
                f"after {stall:.0f} s without one)")
            noted = True
        finished = [f for f in futures if f.status in ("finished", "error", "cancelled", "lost")]
        if finished:
            last_done, noted = time.monotonic(), False
        for future in finished:
            chunk, indices = futures.pop(future)
            if future.status != "finished":
                if future.status == "error":
                    exc = future.exception()
                    text = exception_text(exc)
                    hint = ("" if "would differ" in text else
                            " (are rockslide and its dependencies installed on the workers?)")
                    raise CaseError(f"a task failed on the cluster: {type(exc).__name__}: {text}{hint}",
                                    source="scheduler")
                raise _workers_lost(address, store) if _no_workers(client) else _lost(address, store)
            try:
                states = np.asarray(future.result(timeout=SCHEDULER_TIMEOUT), dtype=np.float64)
            except Exception:  # noqa: BLE001 - the result could not be fetched: the scheduler is gone
                raise _lost(address, store) from None
            store.save(chunk, indices, states)
            if progress is not None:
                progress(indices.size)
        if client.status == "running":
            lost_since = None
        elif lost_since is None:
            lost_since = time.monotonic()
        elif time.monotonic() - lost_since > SCHEDULER_TIMEOUT:
            raise _lost(address, store)
        if lost_since is None and time.monotonic() - checked > 1.0:
            checked = time.monotonic()
            if not _no_workers(client):
                no_workers_since = None
            elif no_workers_since is None:
                no_workers_since = checked
            elif checked - no_workers_since > SCHEDULER_TIMEOUT:
                raise _workers_lost(address, store)
        if not finished:
            time.sleep(0.1)


def _lost(address: str, store: ChunkStore) -> CaseError:
    return CaseError(f"lost the connection to the dask scheduler at {address}; {store.count()} finished "
                     f"chunks are kept in {store.folder} and the same command resumes from them",
                     source="scheduler")


def _workers_lost(address: str, store: ChunkStore) -> CaseError:
    return CaseError(f"every worker of the dask scheduler at {address} is gone (the scheduler still answers); "
                     f"{store.count()} finished chunks are kept in {store.folder}: start workers and the same "
                     "command resumes from them", source="scheduler")


def _no_workers(client) -> bool:
    """Whether the scheduler has no worker (a question to it; False when it cannot be asked)."""
    try:
        return not client.nthreads()
    except Exception:  # noqa: BLE001 - the scheduler is gone: `_lost` says so
        return False


def _wait_for_workers(client, address: str, wait: float | None, say) -> None:
    """Return once the scheduler has a worker; wait up to ``wait`` seconds for the first to join
    (saying once that it waits), Ctrl-C checked, then one line naming ``--wait-workers``."""
    wait = WAIT_FOR_WORKERS if wait is None else wait
    deadline = time.monotonic() + wait
    said = False
    while not client.nthreads():
        if time.monotonic() >= deadline:
            raise CaseError(f"no dask worker joined the scheduler at {address} within {wait:g} s (start workers "
                            f"with 'dask worker {address}', or wait longer with --wait-workers SECONDS)",
                            source="scheduler")
        if not said:
            say(f"  waiting for a first dask worker to join {address} (up to {wait:g} s, --wait-workers)")
            said = True
        interrupts.check()
        time.sleep(0.2)


def worker_identity(expected: dict | None = None) -> dict:
    """What makes a worker's results this client's: rockslide's version, the compiled core's
    source stamp and numba's version; where these are ``expected``'s (the client's), also whether
    its batch kernel is in numba's cache there (``warm``: else its first task compiles it,
    `cold_workers_note`); or why rockslide cannot be imported there. A worker of another core is
    not asked: loading its kernel would refresh a cache folder it may share with other workers.

    Sent to the workers by value (it names no module-level object of rockslide), so that a worker
    without rockslide answers with the reason instead of failing to unpickle the task.
    """
    try:
        import numba

        from rockslide._version import __version__
        from rockslide.core import compiled
        identity = {"rockslide": __version__, "core": compiled.source_stamp(), "numba": numba.__version__}
        if expected is not None and all(identity[k] == expected.get(k) for k in identity):
            from rockslide.core import batch
            identity["warm"] = compiled.is_warm(batch.run_batch)
        return identity
    except Exception as exc:  # noqa: BLE001 - any reason a worker cannot import rockslide is the answer
        return {"error": f"{type(exc).__name__}: {exc}"}


worker_identity.__module__ = "__main__"     # cloudpickle sends functions of __main__ by value


@functools.cache
def _own_identity() -> dict:
    """`local_identity`, once per process (a worker checks it for every task)."""
    return local_identity()


def local_identity() -> dict:
    """`worker_identity` of this process."""
    return worker_identity()


def cold_workers_note(identities: dict) -> str | None:
    """What to say once when some workers (``{worker address: worker_identity()}``) have no compiled
    batch kernel in their numba cache: their first task compiles it (a minute or two), which would
    otherwise look like a cluster that hangs. None when every worker is warm."""
    cold = sorted(w for w, i in identities.items() if i.get("warm") is False)
    if not cold:
        return None
    names = ", ".join(cold[:3]) + (f" and {len(cold) - 3} more" if len(cold) > 3 else "")
    return (f"rockslide: note: {len(cold)} of {len(identities)} dask workers ({names}) compile the batch kernel "
            "first (about a minute on 2 cores, once per machine: their numba cache holds none for this rockslide)")


def check_workers_match(identities: dict, mine: dict, address: str) -> None:
    """Refuse a cluster whose workers (``{worker address: worker_identity()}``) cannot import
    rockslide or run another version of it, another core or another numba than ``mine``: one line
    naming the workers and both versions (their results would differ from this client's)."""
    broken = {w: i["error"] for w, i in identities.items() if "error" in i}
    if broken:
        names = ", ".join(sorted(broken)[:3]) + (f" and {len(broken) - 3} more" if len(broken) > 3 else "")
        raise CaseError(f"the dask worker{'s' if len(broken) > 1 else ''} {names} cannot import rockslide "
                        f"({next(iter(broken.values()))}); install rockslide=={mine['rockslide']} there",
                        source="scheduler")
    for what, name in (("rockslide", "rockslide"), ("core", "rockslide's compiled core (source stamp)"),
                       ("numba", "numba")):
        other = {w: i[what] for w, i in identities.items() if i.get(what) != mine[what]}
        if other:
            workers = sorted(other)
            names = ", ".join(workers[:3]) + (f" and {len(workers) - 3} more" if len(workers) > 3 else "")
            theirs = other[workers[0]]
            shown = (theirs[:12], mine[what][:12]) if what == "core" else (theirs, mine[what])
            several = len(workers) > 1
            raise CaseError(f"the dask worker{'s' if several else ''} {names} run{'' if several else 's'} "
                            f"{name} {shown[0]}, this client {shown[1]}: their results would differ; install the "
                            "same version on every worker", source="scheduler")


@dataclass(frozen=True)
class Scheduler:
    """A dask cluster to compute on, found before any planning (`find_scheduler`).

    Attributes
    ----------
    address : str
        The scheduler's address (``tcp://HOST:PORT``, ``tls://HOST:PORT``, or what a cluster
        object gives).
    security : distributed.Security or None
        The credentials that reach it: one object for the first contact (`identify_scheduler`)
        and the client; None for dask's defaults.
    client : distributed.Client or None
        A client the caller connected: used as is and never closed by rockslide.
    """

    address: str
    security: object = None
    client: object = None

    def __str__(self) -> str:
        return self.address


#: The TLS options of the commands that take ``--scheduler``, named as dask's own command line
#: names them: ``(distributed.Security field, option, dask configuration key)``. Without the
#: option, the key (or its environment variable, ``DASK_DISTRIBUTED__COMM__TLS__CA_FILE``...) holds.
TLS_OPTIONS = (("tls_ca_file", "--tls-ca-file", "distributed.comm.tls.ca-file"),
               ("tls_client_cert", "--tls-cert", "distributed.comm.tls.client.cert"),
               ("tls_client_key", "--tls-key", "distributed.comm.tls.client.key"))


def scheduler_address(address: str, *, default_scheme: str = "tcp") -> str:
    """``tcp://HOST:PORT`` or ``tls://HOST:PORT`` from ``--scheduler`` (``HOST:PORT`` taken as
    ``default_scheme``), or a CaseError. ``inproc://`` exists only inside one Python process, and
    other schemes need their own dask packages: give their cluster or client through the Python API."""
    from urllib.parse import urlsplit

    text = str(address).strip()
    if "://" not in text:
        text = f"{default_scheme}://{text}"
    scheme = text.split("://", 1)[0].lower()
    if scheme not in ("tcp", "tls"):
        raise CaseError(f"{scheme}:// addresses are not supported; expected tcp://HOST:PORT or tls://HOST:PORT "
                        "(a scheduler started with 'dask scheduler'; from Python, a cluster object or a "
                        "distributed.Client can be given as scheduler=)", source="scheduler")
    try:
        parts = urlsplit(text)
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or not port:
        raise CaseError(f"expected an address like {scheme}://HOST:PORT, got {_shown(address)}",
                        source="scheduler")
    return text


def scheduler_security(address: str, tls: dict | None = None):
    """The `distributed.Security` that reaches ``address``, or None for plain TCP.

    ``tls`` maps the fields of `TLS_OPTIONS` to the files given on the command line (None: not
    given); the fields not given come from dask's configuration, as `distributed.Security` reads
    it. A ``tls://`` address needs a CA certificate and a client certificate; each file must be
    readable and load (one CaseError naming the option, or the configuration key, that gave it).
    TLS files with a ``tcp://`` address are refused: the connection would not use them.
    """
    given = {field: str(value) for field, value in (tls or {}).items() if value is not None}
    options = {field: option for field, option, _ in TLS_OPTIONS}
    if not address.lower().startswith("tls://"):
        if given:
            raise CaseError(f"is for a TLS scheduler, but --scheduler {address} is plain TCP (give its tls://HOST:PORT "
                            "address)", source=options[next(iter(given))])
        return None
    import ssl

    from distributed import Security

    security = Security(require_encryption=True, **given)
    where = {field: option if field in given else f"dask's configuration {key}" for field, option, key in TLS_OPTIONS}
    if not security.tls_ca_file or not security.tls_client_cert:
        raise CaseError(f"{address} is a TLS scheduler: give the cluster's CA certificate and this client's "
                        "certificate with --tls-ca-file and --tls-cert (and --tls-key unless the key is in the "
                        "certificate file), or in dask's configuration (distributed.comm.tls.ca-file, "
                        "distributed.comm.tls.client.cert and .key)", source="scheduler")
    for field, _, _ in TLS_OPTIONS:
        value = getattr(security, field)
        if value and "\n" not in value:            # a file name (dask also takes the PEM text itself)
            try:
                with open(value, "rb") as file:
                    file.read(1)
            except OSError as exc:
                raise CaseError(f"cannot read {value}: {exc.strerror or exception_text(exc)}",
                                source=where[field]) from None
    try:
        security.get_connection_args("client")
    except (ssl.SSLError, OSError, ValueError) as exc:
        try:
            ssl.create_default_context(cafile=None if "\n" in security.tls_ca_file else security.tls_ca_file,
                                       cadata=security.tls_ca_file if "\n" in security.tls_ca_file else None)
        except (ssl.SSLError, OSError, ValueError):
            raise CaseError(f"{security.tls_ca_file} is not a CA certificate in PEM format ({exception_text(exc)})",
                            source=where["tls_ca_file"]) from None
        key = security.tls_client_key
        raise CaseError(f"cannot load this client's certificate {security.tls_client_cert} and key "
                        f"{key or '(in the certificate file)'}: {exception_text(exc)} (a PEM certificate and the key "
                        f"that belongs to it{', ' + where['tls_client_key'] if key else ''})",
                        source=where["tls_client_cert"]) from None
    return security


def find_scheduler(scheduler, tls: dict | None = None, *, identify: bool = True) -> Scheduler:
    """The dask cluster ``scheduler`` names, asked who it is (`identify_scheduler`) unless not
    ``identify``: before any planning, so that a mistyped address or a wrong certificate is said at
    once.

    Parameters
    ----------
    scheduler : str, Scheduler, distributed.Client or cluster object
        An address (``tcp://HOST:PORT``, ``tls://HOST:PORT``; `scheduler_address`), a connected
        client (used as is, not closed), or a cluster object with ``scheduler_address`` and
        optionally ``security`` (dask-jobqueue's ``SLURMCluster``, dask-gateway's
        ``GatewayCluster``, ``distributed.LocalCluster``), reached with its own security.
    tls : dict, optional
        For an address: the TLS files given on the command line (`scheduler_security`).

    Raises
    ------
    CaseError
        A bad address, missing or unreadable certificates, nothing (or no dask scheduler) at the
        address, a certificate refused; a closed client; an object that is neither.
    """
    if isinstance(scheduler, Scheduler):
        return scheduler
    if isinstance(scheduler, str):
        given = any(value is not None for value in (tls or {}).values())
        address = scheduler_address(scheduler, default_scheme="tls" if given else "tcp")
        found = Scheduler(address, scheduler_security(address, tls))
    else:
        if any(value is not None for value in (tls or {}).values()):
            raise CaseError("TLS files go with an address; a client or a cluster object brings its own security",
                            source="scheduler")
        try:
            import distributed
        except ImportError:  # pragma: no cover - a declared dependency
            raise CaseError("needs dask.distributed (pip install 'dask[distributed]')", source="scheduler") from None
        if isinstance(scheduler, distributed.Client):
            if scheduler.asynchronous or scheduler.status != "running":
                state = "asynchronous" if scheduler.asynchronous else scheduler.status
                raise CaseError(f"the distributed.Client given is {state}; give a running, synchronous client, or "
                                "its cluster or address", source="scheduler")
            return Scheduler(scheduler.scheduler.address, client=scheduler)
        address = getattr(scheduler, "scheduler_address", None)
        if not isinstance(address, str) or not address:
            raise CaseError(f"expected an address (tcp://HOST:PORT), a distributed.Client or a cluster object with a "
                            f"scheduler_address, got {type(scheduler).__name__}", source="scheduler")
        found = Scheduler(address, getattr(scheduler, "security", None))
    if identify:
        with _quiet_dask():
            identify_scheduler(found.address, security=found.security)
    return found


def identify_scheduler(address: str, timeout: float | None = None, *, security=None) -> dict:
    """Ask ``address`` who it is, within ``timeout`` seconds in all (default
    :data:`SCHEDULER_TIMEOUT`), with ``security``'s credentials (a `distributed.Security`; None:
    dask's defaults): a dask scheduler answers the ``identity`` request; anything else (nothing
    listening, an HTTP server, a certificate refused either way) is a CaseError."""
    timeout = SCHEDULER_TIMEOUT if timeout is None else timeout
    import asyncio
    import socket
    from concurrent.futures import ThreadPoolExecutor
    from urllib.parse import urlsplit

    from distributed.comm import connect

    parts = urlsplit(address)
    if parts.scheme in ("tcp", "tls"):
        try:
            socket.create_connection((parts.hostname, parts.port), timeout=timeout).close()
        except OSError as exc:       # refused, unreachable: at once (dask itself retries until its timeout)
            raise CaseError(f"cannot connect to the dask scheduler at {address}: "
                            f"{exc.strerror or exception_text(exc)}", source="scheduler") from None
    try:
        arguments = security.get_connection_args("client") if security is not None else {}
    except Exception as exc:  # noqa: BLE001 - a cluster object's credentials that do not load
        raise CaseError(f"the TLS credentials for {address} cannot be loaded: {exception_text(exc)}",
                        source="scheduler") from None

    async def ask():
        comm = await connect(address, timeout=timeout, **arguments)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        with ThreadPoolExecutor(1) as pool:         # its own event loop, even under a running one
            reply = pool.submit(asyncio.run, asyncio.wait_for(ask(), timeout)).result()
    except TimeoutError:
        raise CaseError(f"no dask scheduler answered at {address} within {timeout:g} s (is something "
                        "else listening there?)", source="scheduler") from None
    except Exception as exc:  # noqa: BLE001 - refused, reset, closed, a bad handshake
        raise CaseError(f"cannot connect to the dask scheduler at {address}: {_connection_failure(exc, address)}",
                        source="scheduler") from None
    if not (isinstance(reply, dict) and reply.get("type") == "Scheduler"):
        raise CaseError(f"{address} answers, but not as a dask scheduler", source="scheduler")
    return reply


def _connection_failure(exc: BaseException, address: str) -> str:
    """Why a first contact failed, in words: a certificate refused by either side (TLS), a reset
    (a TLS scheduler reached over plain TCP), or the library's own reason."""
    import ssl

    chain, cause = [], exc
    while cause is not None and len(chain) < 8:
        chain.append(cause)
        cause = cause.__cause__ or cause.__context__
    text = " ".join(exception_text(e) for e in chain)
    if any(isinstance(e, ssl.SSLCertVerificationError) for e in chain) or "CERTIFICATE_VERIFY_FAILED" in text:
        return ("the scheduler's certificate was not accepted: it is not signed by the CA certificate given "
                "(--tls-ca-file, or dask's distributed.comm.tls.ca-file)")
    refused = ("ALERT_UNKNOWN_CA", "ALERT_BAD_CERTIFICATE", "CERTIFICATE_REQUIRED", "ALERT_CERTIFICATE",
               "EOF occurred in violation of protocol")   # TLS 1.3: the scheduler hangs up after the handshake
    tls = address.lower().startswith("tls://")
    if any(word in text for word in refused) or tls and any(isinstance(e, ssl.SSLEOFError) for e in chain):
        return ("this client's certificate was not accepted by the scheduler: is it signed by the cluster's CA? "
                "(--tls-cert, or dask's distributed.comm.tls.client.cert)")
    if tls and "convert to SSL" in text:          # the server spoke first, in plain TCP
        return "it does not speak TLS (a plain TCP scheduler: give its tcp:// address, without TLS files)"
    if tls and any(isinstance(e, ssl.SSLError) for e in chain):
        return f"the TLS handshake failed (is it a TLS scheduler?): {exception_text(chain[-1])}"
    if not tls and "reset by peer" in text:
        return "the connection was reset (a TLS scheduler? give its tls:// address and certificates)"
    return getattr(exc, "strerror", None) or exception_text(exc)


@contextlib.contextmanager
def _quiet_dask():
    """The cluster's log messages and dask's table of mismatched package versions kept off the
    terminal (`check_workers_match` says what matters; errors are reported in one line)."""
    with _quiet_logs("distributed", "tornado", "asyncio"), warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*[Mm]ismatched versions.*")
        yield


@contextlib.contextmanager
def _quiet_logs(*prefixes: str):
    """Keep the log messages of these libraries off the terminal (errors are reported in one line)."""
    import logging

    names = [n for n in list(logging.root.manager.loggerDict) if n.split(".")[0] in prefixes]
    loggers = [logging.getLogger(n) for n in {*names, *prefixes}]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)


def _shown(text: str, limit: int = 80) -> str:
    text = repr(str(text))
    return text if len(text) <= limit else text[:limit - 4] + "...'"
