"""Every ```python block of README.md and docs/*.md runs as a user runs it: saved to a file and
started with ``python file.py`` in a subprocess, from the repository root (the blocks name
``scenarios/...`` relative to it). Inside pytest a study's worker processes cannot re-import a
script, so only a subprocess shows what a user's script does.

Shortening, the one mechanism: an HTML comment on the lines right above a block,

    <!-- docs-test: replace `OLD` with `NEW` -->

makes this test run the block with OLD replaced by NEW (each OLD must occur in the block, so a
stale marker fails). The comment sits in the Markdown source beside the block it shortens; the
page shows the block as written. ``FLEXMVM_DOCS_FULL=1`` in the environment (read by this test
only, never by flexmvm) runs every block as written.

The pages are README.md and every page of the documentation site (the Markdown sources in
docs/, lab notes in docs/notes/ included); the site's build does not run them again. A block
that occurs on several pages (the first script of README.md and docs/getting_started.md) runs
once. Tutorial code shown from a file (```{literalinclude} ../examples/NAME.py```) is run by
tests/test_examples.py, which runs every script of examples/.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [
    ROOT / "README.md",
    *sorted(p for p in (ROOT / "docs").rglob("*.md") if "_build" not in p.parts),
]
MARKER = re.compile(r"^<!-- docs-test: replace `([^`]+)` with `([^`]*)` -->$")
# Each block's wall-time budget [s]. The longest, README's first script (two runs on 20 us of
# the short seed case; the same block on docs/getting_started.md runs once), took 27-54 s on the
# shared 2-core machine at load 13-21 with the kernels compiled; 300 s leaves room for a cold
# numba and setup cache on a quieter machine.
BUDGET_S = 300.0


def _blocks(page: Path) -> list[tuple[str, str, list[tuple[str, str]]]]:
    """(label, code, replacements) of every ```python block of ``page``."""
    lines = page.read_text(encoding="utf-8").splitlines()
    out, i = [], 0
    while i < len(lines):
        if lines[i].strip() != "```python":
            i += 1
            continue
        subs, k = [], i - 1
        while k >= 0 and (m := MARKER.match(lines[k].strip())):
            subs.insert(0, m.groups())
            k -= 1
        j = lines.index("```", i + 1)
        out.append((f"{page.relative_to(ROOT)}:{i + 1}", "\n".join(lines[i + 1 : j]) + "\n", subs))
        i = j + 1
    return out


def _unique(blocks):
    """The blocks whose code and replacements differ from those of every earlier block."""
    seen, out = set(), []
    for label, code, subs in blocks:
        key = (code, tuple(subs))
        if key not in seen:
            seen.add(key)
            out.append((label, code, subs))
    return out


ALL_BLOCKS = [b for page in PAGES for b in _blocks(page)]
BLOCKS = _unique(ALL_BLOCKS)
INCLUDE = re.compile(r"^```\{literalinclude\} (\S+)$")


def test_the_pages_have_python_blocks():
    """README's library example, the getting-started page's and the scenario-format page's
    are found (a broken extraction would make the test below vacuous)."""
    labels = {label.split(":")[0] for label, _, _ in ALL_BLOCKS}
    assert {"README.md", "docs/scenario_format.md", "docs/getting_started.md"} <= labels


def test_tutorial_code_is_run_by_a_test():
    """Every file a page shows by ``literalinclude`` is a script of examples/, which
    tests/test_examples.py runs (it checks that it covers every one); the tutorials show at
    least the three examples. Reads the pages only: well under a second."""
    shown = set()
    for page in PAGES:
        for line in page.read_text(encoding="utf-8").splitlines():
            if m := INCLUDE.match(line.strip()):
                path = (page.parent / m.group(1)).resolve()
                assert path.parent == ROOT / "examples" and path.suffix == ".py", (
                    f"{page.relative_to(ROOT)} shows {m.group(1)}, not a script of examples/"
                )
                assert path.is_file(), f"{page.relative_to(ROOT)} shows {m.group(1)}: no such file"
                shown.add(path.name)
    assert shown >= {"rod_impact.py", "selection_study.py", "pendulum_joints.py"}


def test_api_reference_lists_the_fm_surface():
    """docs/api_reference.md has an autodoc entry for every name of ``flexmvm.__all__`` (the
    docs build checks the same; this catches it in the test run). Well under a second."""
    import flexmvm

    page = (ROOT / "docs" / "api_reference.md").read_text(encoding="utf-8")
    missing = [n for n in flexmvm.__all__ if f":: flexmvm.{n}\n" not in page]
    assert not missing, f"docs/api_reference.md: no entry for {missing}"


@pytest.mark.parametrize("label, code, subs", BLOCKS, ids=[b[0] for b in BLOCKS])
def test_python_block_runs_as_a_script(tmp_path, label, code, subs):
    """Exit status 0 within BUDGET_S, and nothing on stderr but warnings of one line plus the
    source line Python shows with them: no traceback, no worker re-running the script."""
    if os.environ.get("FLEXMVM_DOCS_FULL") != "1":
        for old, new in subs:
            assert old in code, f"{label}: docs-test marker replaces {old!r}, not in the block"
            code = code.replace(old, new)
    script = tmp_path / "block.py"
    script.write_text(code, encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, str(script)],
        check=False,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=BUDGET_S,
    )
    assert proc.returncode == 0, f"{label}:\n{proc.stderr[-3000:]}"
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert "bootstrapping phase" not in proc.stderr
