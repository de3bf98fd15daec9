"""The Python quick start (python/README.md) runs as written (from a
checkout's root: here a temporary folder that links the repository's
data)."""

import os
import re

from conftest import ROOT


def test_readme_python_quick_start_runs(tmp_path, monkeypatch):
    readme = (ROOT / "python" / "README.md").read_text(encoding="utf-8")
    section = readme[readme.index("## Quick start"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    (tmp_path / "data").symlink_to(ROOT / "data")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    assert (tmp_path / "out" / "calibration.json").exists()
    assert os.path.getsize(tmp_path / "out" / "calibration.json") > 1000
