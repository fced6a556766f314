"""The documentation runs: every ```python block of README.md and docs/*.md, as written, in order.

The blocks of one file share one namespace, like a notebook, and run from a scratch folder that
sees the repository's files (each top-level entry linked in) but not its ``out/``: a block reads
``tests/fixtures/...`` as a newcomer at the repository root would, and what it writes under
``out/`` lands in the scratch folder. A block that raises fails the test with the file, the
block's number, the Markdown line and its source. Blocks that must not run use another fence
language (```text, ```console, ```bash).
"""

from __future__ import annotations

import os
import re
import traceback
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
README_MAX_LINES = 300

FENCE = re.compile(r"^(`{3,})\s*([^`\s]*)")


def code_blocks(path: Path) -> list[tuple[str, int, str]]:
    """``(language, first code line (1-based), source)`` of each fenced block of a Markdown file."""
    blocks: list[tuple[str, int, str]] = []
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if opening is None:
            i += 1
            continue
        fence, language = opening.group(1), opening.group(2).lower()
        j = i + 1
        while j < len(lines) and not (lines[j].startswith(fence) and lines[j].strip() == fence):
            j += 1
        if j == len(lines):
            raise AssertionError(f"{path.name}:{i + 1}: a code block opened here is never closed")
        blocks.append((language, i + 2, "\n".join(lines[i + 1:j])))
        i = j + 1
    return blocks


def python_blocks(path: Path) -> list[tuple[int, str]]:
    return [(start, source) for language, start, source in code_blocks(path) if language == "python"]


def _shown(path: Path) -> str:
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def run_blocks(path: Path) -> None:
    """Run the python blocks of ``path`` in order in one namespace; fail naming the block that raised."""
    namespace: dict[str, object] = {"__name__": "__main__"}
    md_lines = path.read_text(encoding="utf-8").splitlines()
    for number, (start, source) in enumerate(python_blocks(path), 1):
        # padded so that line numbers in tracebacks are the Markdown file's own
        code = compile("\n" * (start - 1) + source, str(path), "exec")
        failure = None
        try:
            exec(code, namespace)
        except Exception as exc:  # any failure of a documented block is the finding
            frames = [f for f in traceback.extract_tb(exc.__traceback__) if f.filename == str(path)]
            line = frames[-1].lineno if frames else start
            failure = (f"{_shown(path)}: python block {number} (line {start}) raised "
                       f"{type(exc).__name__}: {exc}\n  at {path.name}:{line}: {md_lines[line - 1].strip()}\n\n"
                       + "".join(traceback.format_exception(exc)))
        if failure is not None:
            pytest.fail(failure, pytrace=False)


@pytest.fixture
def scratch_root(tmp_path, monkeypatch) -> Path:
    """A working folder that sees the repository's top-level entries (linked), except ``out/``."""
    for entry in ROOT.iterdir():
        if entry.name.startswith(".") or entry.name == "out":
            continue
        (tmp_path / entry.name).symlink_to(entry, target_is_directory=entry.is_dir())
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("path", DOCUMENTS, ids=[_shown(p) for p in DOCUMENTS])
def test_python_blocks_run(path, scratch_root):
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    try:
        run_blocks(path)
    finally:
        plt.close("all")
    written = scratch_root / "out"
    stray = [p.name for p in scratch_root.iterdir() if not p.is_symlink() and p != written]
    assert not stray, f"{path.name}: blocks wrote outside out/: {stray}"


@pytest.mark.parametrize("path", DOCUMENTS, ids=[_shown(p) for p in DOCUMENTS])
def test_no_python_block_hides_under_another_name(path):
    """A block fenced ```py or ```python3 would silently not run: fence Python as ```python."""
    odd = [(start, language) for language, start, _ in code_blocks(path)
           if language.startswith("py") and language != "python"]
    assert not odd, f"{path.name}: python under another fence name at (line, language) {odd}"


def test_readme_is_a_guide_that_runs():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    lines = text.splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines, more than {README_MAX_LINES}"
    # the two commands come first: CI and newcomers rely on them
    assert lines[2] == "```bash" and lines[5] == "```", lines[2:6]
    assert lines[3].startswith("make demo ") and lines[4].startswith("make test "), lines[3:5]
    assert python_blocks(ROOT / "README.md"), "README.md has no python block left to run"


@pytest.mark.parametrize("path", DOCUMENTS, ids=[_shown(p) for p in DOCUMENTS])
def test_relative_links_resolve(path):
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", path.read_text(encoding="utf-8"))
    missing = [t for t in targets if "://" not in t and not (path.parent / t).exists()]
    assert not missing, f"{path.name}: links to missing files {missing}"


def test_scratch_root_keeps_out_apart(scratch_root):
    assert (scratch_root / "tests" / "fixtures" / "borealtc").is_dir()
    assert not (scratch_root / "out").exists()
    assert Path(os.getcwd()).resolve() == scratch_root.resolve()
