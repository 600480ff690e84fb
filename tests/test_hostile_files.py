"""Shared output folders and result files from someone else (issue 28, the two security holes):
temporary files are created exclusively and never through a link, and a result file is read as
data only (no external link, soft link, external storage or virtual dataset is followed)."""

from __future__ import annotations

import os
import shutil

import h5py
import numpy as np
import pytest
from conftest import REPO, _case, invoke, one_line_error

from rockslide.io import files

posix = pytest.mark.skipif(os.name != "posix", reason="symbolic links and pids as on POSIX")




@posix
def test_planted_links_at_the_temporary_names_redirect_nothing(tmp_path):
    """Someone who can write in the output folder plants links at the names of this process's next
    temporaries (``.NAME.h5.<pid>.<place>.tmp``, ``.NAME.png.<pid>.<place>.tmp``) pointing at a file of the user's:
    the run succeeds, the victim is untouched, and the published files are regular files."""
    _case(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    victim = tmp_path / "precious.txt"
    victim.write_text("the user's thesis\n")
    for name in ("example.h5", "example.png"):
        os.symlink(victim, files.temporary_path(out / name))
    done = invoke("run", tmp_path / "case.yaml", "--records-dir", tmp_path)
    assert done.exit_code == 0, done.output
    assert victim.read_text() == "the user's thesis\n"
    for name in ("example.h5", "example.png"):
        assert (out / name).is_file() and not (out / name).is_symlink()
    assert not list(out.glob(".*.tmp"))


@posix
def test_open_new_never_writes_through_a_link_nor_into_an_existing_file(tmp_path):
    victim = tmp_path / "victim"
    victim.write_bytes(b"keep")
    link = tmp_path / ".x.tmp"
    os.symlink(victim, link)
    with files.open_new(link) as handle:
        handle.write(b"new")
    assert victim.read_bytes() == b"keep" and link.read_bytes() == b"new" and not link.is_symlink()
    with pytest.raises(IsADirectoryError):
        (tmp_path / "d").mkdir()
        files.open_new(tmp_path / "d")


@pytest.fixture(scope="module")
def result_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("result")
    _case(folder)
    assert invoke("run", folder / "case.yaml", "--records-dir", folder, "--no-plot").exit_code == 0
    return folder / "out" / "example.h5"


def _hostile(result_file, tmp_path, change):
    path = tmp_path / "hostile.h5"
    shutil.copy(result_file, path)
    with h5py.File(path, "a") as f:
        change(f, tmp_path)
    return path


def _external_link(f, folder):
    other = folder / "other.h5"
    with h5py.File(other, "w") as g:
        g["secret"] = np.arange(5.0)
    f["leak"] = h5py.ExternalLink(str(other), "/secret")


def _external_storage(f, folder):
    victim = folder / "passwd"
    victim.write_bytes(b"root:x:0:0:root:/root:/bin/bash\n" * 8)
    del f["ground/horizontal"]
    f["ground"].create_dataset("horizontal", shape=(32,), dtype="f8", external=[(str(victim), 0, 256)])


def _soft_link_loop(f, folder):
    f["loop"] = h5py.SoftLink("/loop")


def _virtual(f, folder):
    other = folder / "source.h5"
    with h5py.File(other, "w") as g:
        g["x"] = np.arange(4.0)
    layout = h5py.VirtualLayout(shape=(4,), dtype="f8")
    layout[:] = h5py.VirtualSource(str(other), "x", shape=(4,))
    f.create_virtual_dataset("virtual", layout)


@pytest.mark.parametrize("change", [_external_link, _external_storage, _soft_link_loop, _virtual],
                         ids=["external-link", "external-storage", "soft-link-loop", "virtual-dataset"])
def test_a_result_that_points_elsewhere_is_refused_in_one_line(result_file, tmp_path, change):
    path = _hostile(result_file, tmp_path, change)
    line = one_line_error(invoke("plot", path, "-o", tmp_path / "figure.png"), "hostile.h5", "not read:")
    assert "holds all its data itself" in line
    assert not (tmp_path / "figure.png").exists()


# --------------------------------------------------------------------------------------------------
# Issue 28.8: hostile contents are one line and exit 2, never "internal error" (validated in one
# place, io/results.py, before anything is drawn)
# --------------------------------------------------------------------------------------------------


def _infinite_direction(f, folder):
    f.attrs["direction"] = np.inf


def _claims_to_be_a_sweep(f, folder):
    f.attrs["format"] = "rockslide-sweep"


def _claims_to_be_a_fragility(f, folder):
    f.attrs["format"] = "rockslide-fragility"


def _unequal_columns(f, folder):
    rotation = f["time_history/rotation"][()]
    del f["time_history/rotation"]
    f["time_history/rotation"] = rotation[:-3]


def _all_nan_columns(f, folder):
    for column in f["time_history"].values():
        if column.dtype.kind == "f":
            column[...] = np.nan


def _a_trillion_rows_declared(f, folder):
    del f["time_history/rotation"]
    f["time_history"].create_dataset("rotation", shape=(10**12,), dtype="f8", chunks=(10**6,))


def _a_megabyte_name(f, folder):
    f.attrs["name"] = "x" * 1_000_000


def _a_huge_fixed_attribute(f, folder):
    f.attrs.create("notes", np.zeros(2 * 2**20 // 8))


def _nan_step(f, folder):
    f.attrs["integration_step"] = np.nan


def _dataset_stored_in_a_fifo(f, folder):
    fifo = folder / "pipe"
    os.mkfifo(fifo)
    del f["ground/horizontal"]
    f["ground"].create_dataset("horizontal", shape=(32,), dtype="f8", external=[(str(fifo), 0, 256)])


def _a_floor_base_of_ten_billion_rows(f, folder):
    base = f.create_group("base")              # a block on a floor keeps the ground under the building
    for name in ("time", "horizontal", "vertical"):
        base.create_dataset(name, shape=(10**10,), dtype="f8", chunks=(10**6,))


HOSTILE_CONTENTS = [
    (_infinite_direction, "direction = inf; expected -1, 0 or 1"),
    (_claims_to_be_a_sweep, "damaged rockslide sweep (no variable 'overturned')"),
    (_claims_to_be_a_fragility, "damaged rockslide fragility analysis (no dimension 'level')"),
    (_unequal_columns, "the columns of /time_history have different lengths"),
    (_all_nan_columns, "/time_history holds values that are not finite numbers"),
    (_a_trillion_rows_declared, "declares 1000000000000 rows; rockslide reads at most 1e+08"),
    (_a_megabyte_name, "a name of 1000000 characters; a case's name has at most 200"),
    (_a_huge_fixed_attribute, "attribute 'notes' of / holds 2097152 bytes"),
    (_nan_step, "integration_step = nan; expected a positive step"),
    (_dataset_stored_in_a_fifo, "values live in another file"),
    (_a_floor_base_of_ten_billion_rows, "/base/time declares 10000000000 rows"),
]


@posix
@pytest.mark.parametrize("change, expected", HOSTILE_CONTENTS, ids=[c.__name__[1:] for c, _ in HOSTILE_CONTENTS])
def test_a_hostile_result_is_one_line_and_exit_2(result_file, tmp_path, change, expected):
    """Each file was an "internal error" (exit 1), a minute of drawing or "out of memory"."""
    path = _hostile(result_file, tmp_path, change)
    one_line_error(invoke("plot", path, "-o", tmp_path / "figure.png"), "hostile.h5", expected)
    assert not (tmp_path / "figure.png").exists()


def test_time_options_at_the_edge_of_float_are_a_line_or_the_whole_record(result_file, tmp_path):
    """``--time-shift 1e308s`` was an internal error (ticks of an infinite axis); a crop or window
    beyond the record is clipped to it (was a singular matrix)."""
    one_line_error(invoke("plot", result_file, "--time-shift", "1e308s", "-o", tmp_path / "a.png"),
                   "--time-shift", "beyond +-1e+06 s")
    assert not (tmp_path / "a.png").exists()
    for option in ("--crop=-1e308:1e308", "--window=-1e308:1e308"):
        done = invoke("plot", result_file, option, "-o", tmp_path / "b.png", "--overwrite")
        assert done.exit_code == 0, done.output
        assert (tmp_path / "b.png").stat().st_size > 0


@posix
def test_standard_output_on_a_full_device_is_one_line_and_the_result_stays(tmp_path):
    """``rockslide run ... > /dev/full``: the result is published, then printing fails: one line,
    exit 2, no traceback, the published result intact and readable."""
    import subprocess
    import sys

    from rockslide.io import results

    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full here")
    _case(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    with open("/dev/full", "w") as full:
        done = subprocess.run([sys.executable, "-m", "rockslide.cli", "run", "case.yaml", "--records-dir", ".",
                               "--no-plot"], cwd=tmp_path, stdout=full, stderr=subprocess.PIPE, text=True,
                              env=env, timeout=300)
    lines = done.stderr.splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert lines[0].startswith("rockslide: error: cannot write to standard output: No space left on device")
    assert results.read_result(tmp_path / "out" / "example.h5").name == "example"
