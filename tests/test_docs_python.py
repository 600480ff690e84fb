"""docs/python.md runs as written: its Python blocks, in order, in one namespace, from a folder laid
out as the repository's root (configs/ and records/ beside it; the examples a notebook user copies
must work), so that the files it writes (out/) do not land in the checkout: a `rockslide run
configs/example.yaml` after the tests would find out/example.h5 there and refuse to replace it."""

from __future__ import annotations

import re

from conftest import REPO

PAGE = REPO / "docs" / "python.md"


def test_the_python_page_runs(monkeypatch, tmp_path):
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(), flags=re.S)
    assert len(blocks) >= 4
    for folder in ("configs", "records"):
        (tmp_path / folder).symlink_to(REPO / folder, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    before = _listing(REPO / "out")
    monkeypatch.delenv("ROCKSLIDE_RECORDS", raising=False)
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, str(PAGE), "exec"), namespace)        # noqa: S102 - the page's own examples
    assert namespace["result"].summary.status == "ok"
    assert set(namespace["grid"].dims) == {"mu", "pga"}
    assert "median" in namespace["curves"]
    assert (tmp_path / "out" / "example.h5").is_file() and _listing(REPO / "out") == before


def _listing(folder) -> dict:
    """Each file's name and modification time (nothing for a folder that does not exist)."""
    return {p.name: p.stat().st_mtime_ns for p in folder.iterdir()} if folder.is_dir() else {}
