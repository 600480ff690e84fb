"""Where a plan's finished chunks go: on disk beside the result (`ChunkStore`, resumable after
Ctrl-C or a crash), or in memory (`MemoryStore`, for the Python API's in-memory studies)."""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

import numpy as np

from ..core import layout as L
from ..errors import CaseError, OutputError, exception_text
from ..io.files import atomic_write, remove_stale_temporaries
from .plan import Plan


class ChunkStore:
    """Finished chunks of one sweep definition: ``FOLDER/KEY16/chunk-NNNNNN.npz``.

    ``FOLDER`` is ``.NAME.sweep.chunks`` beside the result file. Each file holds the chunk's flat
    indices, final kernel states and a checksum (SHA-256 of the sweep's key, the indices and the
    states), and is written to a temporary name then renamed, so a file with the chunk's name is
    always complete. A file that cannot be read (truncated, a flipped byte, not an ``.npz``, a
    folder) or does not match the plan (another key, other indices, a wrong checksum) counts as
    missing: it is computed again, and `damaged` says which and why.
    """

    def __init__(self, folder: Path, key: str | None = None):
        self.root = Path(folder)
        self.key = key or ""
        self.folder = self.root / self.key[:16]
        self.damaged: dict[int, str] = {}

    def for_plan(self, key: str) -> ChunkStore:
        """This store for the plan whose definition key is ``key`` (`plan.definition_key`): a store
        made without a key takes the plan's; a store made for another plan is refused (its chunks
        would be another grid's numbers).

        Raises
        ------
        CaseError
            The store was made for another plan.
        """
        if not self.key:
            return ChunkStore(self.root, key)
        if self.key != key:
            raise CaseError(_another_plan(self.key, key, self.root), source="store")
        return self

    @classmethod
    def beside(cls, result_path: Path, key: str) -> ChunkStore:
        """The store for the result file ``OUT/NAME.sweep.h5``: ``OUT/.NAME.sweep.chunks``."""
        result_path = Path(result_path)
        name = result_path.name[:-len(".h5")] if result_path.name.endswith(".h5") else result_path.name
        return cls(result_path.with_name(f".{name}.chunks"), key)

    def path(self, chunk: int) -> Path:
        """The file of chunk ``chunk``."""
        return self.folder / f"chunk-{chunk:06d}.npz"

    def refuse_links(self) -> None:
        """Refuse a chunk folder (or its definition's folder) that is a link: planted in a shared
        output folder, it would send the study's files elsewhere, or feed it chunks from elsewhere."""
        for folder in (self.root, self.folder):
            if os.path.islink(folder):
                raise OutputError("is a link where rockslide keeps a study's chunks; remove it (rockslide never "
                                  "follows a link at a name it makes)", source=str(folder))

    def for_device(self, device: str) -> ChunkStore:
        """The store of the chunks computed on ``device``: this one for ``"cpu"`` (threads or a
        cluster's workers: identical results), one of its own for a GPU, whose fused multiply-adds
        round the last bits their own way, so that a resume never mixes the two."""
        if device == "cpu":
            return self
        return ChunkStore(self.root, hashlib.sha256(f"{self.key}:{device}".encode()).hexdigest())

    def checksum(self, indices: np.ndarray, states: np.ndarray) -> str:
        """SHA-256 of the sweep's key, a chunk's indices and its states (as stored)."""
        digest = hashlib.sha256(self.key.encode())
        digest.update(np.ascontiguousarray(indices, dtype=np.int64).tobytes())
        digest.update(np.ascontiguousarray(states, dtype=np.float64).tobytes())
        return digest.hexdigest()

    def load(self, chunk: int, indices: np.ndarray) -> np.ndarray | None:
        """The final states of ``chunk`` if a matching, intact file is stored, else None (and, for a
        file that exists but cannot be used, the reason in ``damaged[chunk]``)."""
        path = self.path(chunk)
        if not os.path.lexists(path):
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                key, stored, states, checksum = (data["key"], data["indices"], data["states"],
                                                 data["checksum"])
                key, checksum = str(key), str(checksum)
                stored = np.array(stored)
                states = np.array(states, dtype=np.float64)
        except Exception as exc:  # noqa: BLE001 - any way of not being a readable chunk file
            self.damaged[chunk] = exception_text(exc)
            return None
        if key != self.key:
            self.damaged[chunk] = "of another sweep definition"
        elif not np.array_equal(stored, indices) or states.shape != (indices.size, L.N_STATE):
            self.damaged[chunk] = "other cases than the plan's"
        elif checksum != self.checksum(stored, states):
            self.damaged[chunk] = "its checksum does not match its content"
        else:
            self.damaged.pop(chunk, None)
            return states
        return None

    def save(self, chunk: int, indices: np.ndarray, states: np.ndarray) -> None:
        """Store a finished chunk (atomically: a temporary file renamed; whatever was at its name,
        a damaged file or a folder, is replaced)."""
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputError(f"cannot create the chunk folder: {exc.strerror or exc}",
                              source=str(self.folder)) from None
        self.refuse_links()
        path = self.path(chunk)
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        indices = np.ascontiguousarray(indices, dtype=np.int64)
        states = np.ascontiguousarray(states, dtype=np.float64)
        # not synced to disk: a chunk that a power cut damages fails its checksum and is computed again
        with atomic_write(path, overwrite=True, per_thread=True, what="chunk", interruptible=False,
                          sync=False) as handle:
            np.savez(handle, key=np.array(self.key), indices=indices, states=states,
                     checksum=np.array(self.checksum(indices, states)))
        self.damaged.pop(chunk, None)

    def remove_stale_temporaries(self) -> list[Path]:
        """Delete temporary chunk files of processes that are gone (`files.remove_stale_temporaries`)."""
        try:
            names = [p.name for p in self.folder.glob(".chunk-*.tmp")]
        except OSError:
            return []
        finals = {self.folder / (n.split(".npz.")[0][1:] + ".npz") for n in names if ".npz." in n}
        return remove_stale_temporaries(sorted(finals))

    def count(self) -> int:
        """Chunk files stored for this definition."""
        try:
            return sum(1 for p in self.folder.glob("chunk-*.npz"))
        except OSError:  # pragma: no cover
            return 0

    def others(self) -> list[Path]:
        """Chunk folders of other sweep definitions (never used by this one)."""
        try:
            return sorted(p for p in self.root.iterdir() if p.is_dir() and p != self.folder)
        except OSError:
            return []

    def remove(self) -> None:
        """Delete this definition's chunks, and the chunk folder if nothing else is in it."""
        shutil.rmtree(self.folder, ignore_errors=True)
        try:
            self.root.rmdir()
        except OSError:
            pass


def missing_chunks(plan: Plan, store: ChunkStore, out: np.ndarray | None = None) -> list[int]:
    """The chunks of ``plan`` that ``store`` does not hold (a damaged file counts as missing); the
    final states of those it holds go into ``out`` (``float64[n, N_STATE]``) if given, so that
    `collect` reads only the chunks computed afterwards."""
    missing = []
    for chunk in range(plan.n_chunks):
        indices = plan.chunk_indices(chunk)
        states = store.load(chunk, indices)
        if states is None:
            missing.append(chunk)
        elif out is not None:
            out[indices] = states
    return missing


def collect(plan: Plan, store: ChunkStore, chunks=None, out: np.ndarray | None = None) -> np.ndarray:
    """The final states of every case, ``float64[n, N_STATE]`` (flat C order), from the store: of
    ``chunks`` (default: all) into ``out`` (default: a new array).

    Raises
    ------
    OutputError
        A chunk is missing or damaged (it was deleted meanwhile): rerun to compute it.
    """
    out = np.empty((plan.n_cases, L.N_STATE)) if out is None else out
    for chunk in range(plan.n_chunks) if chunks is None else chunks:
        indices = plan.chunk_indices(chunk)
        states = store.load(chunk, indices)
        if states is None:
            raise OutputError(f"chunk {chunk} is missing or damaged; rerun the same command to "
                              "compute it", source=str(store.folder))
        out[indices] = states
    return out


class MemoryStore:
    """Finished chunks held in memory: a `ChunkStore` without files, for studies the caller keeps in
    memory (the Python API's default). Nothing to resume after the process ends."""

    folder = "memory"

    def __init__(self, key: str = ""):
        self.key = key
        self.damaged: dict[int, str] = {}
        self._chunks: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def for_plan(self, key: str) -> MemoryStore:
        """This store for the plan of definition key ``key``: one made without a key takes it; one
        that holds another plan's chunks is refused (`ChunkStore.for_plan`)."""
        if not self.key:
            self.key = key
        elif self.key != key:
            raise CaseError(_another_plan(self.key, key, "memory"), source="store")
        return self

    def path(self, chunk: int) -> str:
        return f"chunk {chunk} in memory"

    def for_device(self, device: str) -> MemoryStore:
        return self                             # nothing kept beyond the study: nothing to mix

    def load(self, chunk: int, indices: np.ndarray) -> np.ndarray | None:
        stored = self._chunks.get(chunk)
        if stored is None or not np.array_equal(stored[0], indices):
            return None
        return stored[1]

    def save(self, chunk: int, indices: np.ndarray, states: np.ndarray) -> None:
        self._chunks[chunk] = (np.array(indices, dtype=np.int64), np.array(states, dtype=np.float64))

    def remove_stale_temporaries(self) -> list:
        return []

    def count(self) -> int:
        return len(self._chunks)

    def others(self) -> list:
        return []

    def remove(self) -> None:
        self._chunks.clear()


def _another_plan(held: str, wanted: str, where) -> str:
    return (f"holds the chunks of another study (definition key {held[:16]}..., in {where}), not of this one "
            f"({wanted[:16]}...): give a store without a key, e.g. ChunkStore(folder), and it takes the plan's")
