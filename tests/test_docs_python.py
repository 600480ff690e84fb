"""docs/python.md runs as written: its Python blocks, in order, in one namespace, from the
repository's root (the examples a notebook user copies must work)."""

from __future__ import annotations

import re

from conftest import REPO

PAGE = REPO / "docs" / "python.md"


def test_the_python_page_runs(monkeypatch):
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(), flags=re.S)
    assert len(blocks) >= 4
    monkeypatch.chdir(REPO)
    monkeypatch.delenv("ROCKSLIDE_RECORDS", raising=False)
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, str(PAGE), "exec"), namespace)        # noqa: S102 - the page's own examples
    assert namespace["result"].summary.status == "ok"
    assert set(namespace["grid"].dims) == {"mu", "pga"}
    assert "median" in namespace["curves"]
