"""The README's Python example runs as written and draws its picture."""

import os
import re

def test_the_readme_example_drapes_and_plots(assets, tmp_path, monkeypatch):
    readme = (assets.parent / "README.md").read_text(encoding="utf-8")
    section = readme[readme.index("## Python") :]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert len([line for line in code.splitlines() if line.strip()]) <= 10
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    exec(compile(code, "README.md", "exec"), {})
    picture = tmp_path / "sheet.png"
    assert picture.exists() and os.path.getsize(picture) > 10_000
