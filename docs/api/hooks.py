"""MkDocs hooks (mkdocs.yml): the root guides become pages; each API page shows its whole ``__all__``.

**Pages.** The Markdown files link to each other by their paths in the repository
(``docs/index.md`` to ``../README.md``, ``README.md`` to ``docs/results.md``), so that the links
work where the files are read, on disk or on a code host. The site serves the two root files as
``guide.md`` and ``architecture.md``; each relative link that names one of the site's pages by its
repository path is rewritten to that page; any other link is left as written, for MkDocs to check.

**Surfaces.** Each API page must document every name of its module's ``__all__`` (read from the
source; nothing is imported): a name missing from the page is a warning, and the build treats
warnings as errors (``strict: true``).

**Known warnings.** A griffe warning listed in :data:`KNOWN_DOCSTRING_WARNINGS` is shown at INFO
level instead: a docstring problem in a module being restructured by someone else, with its fix.
Delete the entry with the fix.
"""

from __future__ import annotations

import ast
import logging
import posixpath
import re
from pathlib import Path

from mkdocs.structure.files import File, Files

#: Repository files outside ``docs/`` that the site serves, and their names in the site.
ROOT_PAGES = {"README.md": "guide.md", "ARCHITECTURE.md": "architecture.md"}
DOCS_DIR = "docs"
#: An inline Markdown link or image target: ``](target)`` or ``](target#anchor)``.
LINK = re.compile(r"\]\((?P<path>[^)#\s:]+)(?P<rest>[^)\s]*)\)")
#: A fenced code block (left untouched): backticks or tildes, three or more, up to the same fence.
FENCE = re.compile(r"^(?P<fence>`{3,}|~{3,})[^\n]*\n.*?^(?P=fence)[ \t]*$", re.MULTILINE | re.DOTALL)

#: The API pages and the module whose ``__all__`` each documents.
API_PAGES = {
    "api/terrain.md": "terrain/__init__.py",
    "api/energy.md": "energy/__init__.py",
    "api/planner.md": "planner/__init__.py",
    "api/errors.md": "terrawatt_base/errors.py",
}
#: The heading mkdocstrings writes for each documented object (its id ends with the object's name).
HEADING_ID = re.compile(r'<h\d id="(?P<id>[^"]+)" class="doc doc-heading')

#: Parts of the messages of griffe warnings shown at INFO level, each with its fix. Matched on the
#: message alone, not the file or line, so that an entry holds while its module is restructured.
KNOWN_DOCSTRING_WARNINGS: tuple[str, ...] = ()

log = logging.getLogger("mkdocs.hooks.terrawatt")


class _KnownWarnings(logging.Filter):
    """Shows the known griffe warnings at INFO level (MkDocs' strict mode counts WARNING and up)."""

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno == logging.WARNING:
            message = record.getMessage()
            if any(part in message for part in KNOWN_DOCSTRING_WARNINGS):
                record.levelno, record.levelname = logging.INFO, "INFO"
        return True


# mkdocstrings routes griffe's messages through this logger ("griffe: <file>:<line>: <message>")
logging.getLogger("mkdocs.plugins.griffe").addFilter(_KnownWarnings())


# ----------------------------------------------------------------------------- pages
def on_files(files: Files, config) -> Files:
    root = Path(config.config_file_path).parent
    for name, uri in ROOT_PAGES.items():
        files.append(File.generated(config, uri, abs_src_path=str(root / name)))
    return files


def _repo_path(src_uri: str) -> str:
    """Where a page of the site lives in the repository (POSIX, relative to its root)."""
    for name, uri in ROOT_PAGES.items():
        if src_uri == uri:
            return name
    return posixpath.join(DOCS_DIR, src_uri)


def _site_uri(repo_path: str) -> str | None:
    """The site's name for a repository file, or None when the site does not serve it."""
    if repo_path in ROOT_PAGES:
        return ROOT_PAGES[repo_path]
    if repo_path.startswith(DOCS_DIR + "/"):
        return repo_path[len(DOCS_DIR) + 1:]
    return None


def on_page_markdown(markdown: str, page, config, files: Files) -> str:
    src_uri = page.file.src_uri
    here = posixpath.dirname(_repo_path(src_uri))

    def relink(match: re.Match[str]) -> str:
        target = posixpath.normpath(posixpath.join(here, match["path"]))
        uri = _site_uri(target)
        if uri is None or files.get_file_from_path(uri) is None:
            return match[0]
        relative = posixpath.relpath(uri, posixpath.dirname(src_uri) or ".")
        return f"]({relative}{match['rest']})"

    pieces, last = [], 0
    for block in FENCE.finditer(markdown):  # links inside code blocks are code, not links
        pieces.append(LINK.sub(relink, markdown[last:block.start()]))
        pieces.append(block[0])
        last = block.end()
    pieces.append(LINK.sub(relink, markdown[last:]))
    return "".join(pieces)


# ----------------------------------------------------------------------------- surfaces
def _exported(path: Path) -> list[str]:
    """The names in a module's ``__all__`` (a literal list or tuple of strings)."""
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
                return list(ast.literal_eval(node.value))
    return []


def on_page_content(html: str, page, config, files: Files) -> str:
    module = API_PAGES.get(page.file.src_uri)
    if module is not None:
        shown = {m["id"].rsplit(".", 1)[-1] for m in HEADING_ID.finditer(html)}
        missing = [n for n in _exported(Path(config.config_file_path).parent / module) if n not in shown]
        if missing:
            log.warning("%s does not document these names of %s's __all__: %s (add each to the page's "
                        "'Documented apart')", page.file.src_uri, module, ", ".join(missing))
    return html
