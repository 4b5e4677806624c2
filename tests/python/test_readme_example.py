"""README.md's Python example runs as written: the first ```python block of its "Python"
section, through `scripts/run python` from the checkout (BUILD_DIR: the build under test),
prints what it says it prints."""
import os
import pathlib
import re
import subprocess

from conftest import REPO


def readme_example():
    text = (REPO / "README.md").read_text()
    section = re.search(r"^## Python\n(.*?)(?=^## )", text, re.S | re.M)
    assert section, "README.md has no '## Python' section"
    block = re.search(r"^```python\n(.*?)^```", section.group(1), re.S | re.M)
    assert block, "the Python section has no ```python example"
    return block.group(1)


def test_readme_example_runs_as_written():
    code = readme_example()
    assert len(code.strip().splitlines()) <= 12, "the example should stay about ten lines"
    env = dict(os.environ)
    assert env.get("BUILD_DIR"), "BUILD_DIR (the build with the module) is not set; run through ctest"
    p = subprocess.run([str(REPO / "scripts" / "run"), "python", "-c", code], cwd=REPO, env=env,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    # The example prints the two potentials and the rollout's error.
    lines = [l for l in p.stdout.splitlines() if l.startswith("E(x) =")]
    assert lines, p.stdout
    assert re.search(r"mean RMSE \d", p.stdout), p.stdout
