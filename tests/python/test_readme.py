# The README's ```python examples run as written (like tests/cli/readme.sh
# for the ```sh ones), in a scratch directory with data/ beside them.
import os
import re

from conftest import ROOT


def test_readme_python_examples_run(tmp_path, monkeypatch):
    blocks = re.findall(r"^```python\n(.*?)^```", (ROOT / "README.md").read_text(), re.S | re.M)
    assert blocks, "no python blocks in README.md"
    os.symlink(ROOT / "data", tmp_path / "data")
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        exec(compile(code, "README.md", "exec"), {})
