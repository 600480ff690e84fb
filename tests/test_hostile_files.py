"""Shared output folders and result files from someone else (issue 28, the two security holes):
temporary files are created exclusively and never through a link, and a result file is read as
data only (no external link, soft link, external storage or virtual dataset is followed)."""

from __future__ import annotations

import os
import shutil

import h5py
import numpy as np
import pytest
import yaml
from conftest import REPO, SHIPPED, invoke, one_line_error

from rockslide.io import files

posix = pytest.mark.skipif(os.name != "posix", reason="symbolic links and pids as on POSIX")


def _case(folder):
    data = yaml.safe_load((REPO / "configs" / "example.yaml").read_text().replace("../records/", ""))
    data["ground"]["tail"] = "0 s"
    data["solver"]["dt"] = "1 ms"
    data["output"] = {"dir": str(folder / "out"), "interval": "10 ms"}
    (folder / "case.yaml").write_text(yaml.safe_dump(data))
    for name in SHIPPED:
        shutil.copy(REPO / "records" / name, folder / name)


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
