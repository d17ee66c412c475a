"""docs/python.md: its ```python blocks run, in order, in one namespace, in
a temporary folder (the tutorial must stay true)."""

import re

import pytest


def test_tutorial_blocks_run(source_dir, tmp_path, monkeypatch):
    text = (source_dir / "docs" / "python.md").read_text()
    blocks = re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)
    assert len(blocks) >= 5
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__tutorial__"}
    for n, code in enumerate(blocks, 1):
        try:
            exec(compile(code, f"docs/python.md block {n}", "exec"), namespace)
        except Exception as e:  # pragma: no cover - the message is the point
            pytest.fail(f"docs/python.md block {n} failed: {type(e).__name__}: {e}\n{code}")
