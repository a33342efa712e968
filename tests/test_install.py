"""The README's install and first-result lines, run as written in a fresh virtual environment.

A copy of the source tree (what ``git ls-files`` lists: no virtual environment, no build outputs) gets the
README's install block run in it by ``bash`` — ``python3 -m venv .venv``, then ``pip install .``, which
builds the wheel and installs it, not an editable link — and the README's "A first result in five minutes"
block then runs in an empty folder with that environment's ``translucency``.  So the lines a newcomer
copies are the lines tested, and the wheel carries everything the commands read (the embedded data, the
examples).  Needs the package index (pip downloads the dependencies): ``make test-install``, not the fast
suite.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"

pytestmark = [pytest.mark.slow, pytest.mark.install]


def readme_block(heading: str) -> list[str]:
    """The command lines of the first ```sh block under ``## heading`` (comments and continuations joined)."""
    text = README.read_text(encoding="utf-8")
    section = text.split(f"## {heading}\n", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    lines, current = [], ""
    for raw in block.splitlines():
        line = raw.split("  #", 1)[0].rstrip()  # a trailing comment, two spaces before its hash
        current += line.rstrip("\\").strip() + " " if line.endswith("\\") else line.strip()
        if not line.endswith("\\") and current:
            lines.append(current)
            current = ""
    return lines


def test_readme_blocks_are_read_as_written():
    """The parser itself: the install block starts with the virtual environment and installs '.'."""
    install = readme_block("Install")
    assert install[0].startswith("python3 -m venv .venv") and "pip install ." in install
    first = readme_block("A first result in five minutes")
    assert [line.split()[1] for line in first] == ["acquire", "fit", "acquire", "evaluate"]


def _source_copy(dest: Path) -> Path:
    """The tracked files of the checkout, copied: what a fresh clone holds."""
    try:
        listed = subprocess.run(
            ["git", "-C", str(ROOT), "ls-files", "-z"], capture_output=True, check=True
        ).stdout.split(b"\0")
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout: no list of the source tree's files")
    for name in filter(None, listed):
        src = ROOT / name.decode()
        if src.is_file():
            (dest / name.decode()).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name.decode())
    return dest


def test_readme_install_and_first_result_in_a_fresh_environment(tmp_path):
    python3 = shutil.which("python3")
    if python3 is None:
        pytest.skip("no python3 on PATH")
    tree = _source_copy(tmp_path / "translucency")
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME")}
    # the install lines, as written, up to the first that installs (the next is the alternative with extras)
    install = readme_block("Install")
    lines = install[: next(i for i, line in enumerate(install) if line.startswith("pip install")) + 1]
    script = "set -e\n" + "\n".join(lines) + "\ntranslucency --version\n"
    done = subprocess.run(
        ["bash", "-c", script], cwd=tree, env=env, capture_output=True, text=True, timeout=1800
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    venv = tree / ".venv"
    site = subprocess.run(
        [str(venv / "bin" / "python"), "-c", "import translucency, sys; print(translucency.__file__)"],
        capture_output=True, text=True, env=env, cwd=tmp_path,
    )  # fmt: skip
    assert "site-packages" in site.stdout, site.stdout + site.stderr  # installed from the wheel, not linked
    assert str(venv) != sys.prefix
    # the first result, in an empty folder, with that environment's command
    work = tmp_path / "work"
    work.mkdir()
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    for line in readme_block("A first result in five minutes"):
        run = subprocess.run(
            ["bash", "-c", line], cwd=work, env=env, capture_output=True, text=True, timeout=1800
        )
        assert run.returncode == 0, f"{line}\n{run.stdout[-2000:]}\n{run.stderr[-2000:]}"
    for made in ("m.zarr", "m.model.zip", "truth.zarr", "report/index.html"):
        assert (work / made).exists(), made
    # the examples travel in the wheel
    ex = subprocess.run(["translucency", "examples", "ex"], cwd=work, env=env, capture_output=True, text=True)
    assert ex.returncode == 0 and (work / "ex" / "spot.obj").is_file(), ex.stderr[-2000:]
