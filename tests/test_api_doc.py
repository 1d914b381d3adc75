"""docs/api.md runs as written: its Python blocks, in order, in one namespace, in a fresh folder."""

from __future__ import annotations

import re
from pathlib import Path

DOC = Path(__file__).resolve().parents[1] / "docs" / "api.md"


def test_every_example_of_the_api_page_runs(tmp_path, monkeypatch, capsys) -> None:
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)
    assert len(blocks) >= 7  # map, mission, pictures, bench, decision env, PettingZoo env, policy
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {}
    for i, code in enumerate(blocks):
        exec(compile(code, f"{DOC.name} block {i + 1}", "exec"), namespace)  # noqa: S102 - the page's own code
    assert (tmp_path / "run.gif").is_file() and (tmp_path / "bench" / "report.md").is_file()
    assert "hier" in capsys.readouterr().out
