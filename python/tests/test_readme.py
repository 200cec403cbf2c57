"""The Python quick start of README.md, run as the README shows it: its block marked
`<!-- snippet: python-quickstart -->` (taken out by scripts/readme-snippet.sh, which every
README test uses) runs in a fresh interpreter, from a directory whose tests/ is the
repository's (the README runs it from the clone's root), and what it prints must end with the
README's block `python-output`. The quick start's to_csr needs scipy, the `scipy` extra the
README installs; the test environment has it."""

import os
import subprocess
import sys

from conftest import REPO


def snippet(name):
    out = subprocess.run(
        ["sh", str(REPO / "scripts" / "readme-snippet.sh"), str(REPO / "README.md"), name],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_readme_python_quick_start_prints_what_the_readme_says(tmp_path):
    code = snippet("python-quickstart")
    want = snippet("python-output").rstrip("\n")
    os.symlink(REPO / "tests", tmp_path / "tests")
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True
    )
    assert out.returncode == 0, f"README.md's Python quick start failed:\n{code}\n{out.stderr}"
    assert out.stdout.rstrip("\n").endswith(want), (
        f"README.md's Python quick start printed\n{out.stdout}\nnot ending with\n{want}"
    )
