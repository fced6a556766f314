"""Griffe extension: the Sphinx roles of the docstrings become links of the API reference.

The docstrings name objects the Sphinx way (``:class:`TerrainMap```, ``:func:`~energy.budget.log_battery_power_w```,
``:meth:`save```) so that ``help()`` and a reader of the source see them as names. The reference
turns each into an optional cross-reference: a link when the object is documented on a page, its
name in code type when it is not (never a warning). Relative names are resolved in the scope of
the docstring's object, like Python would; ``~`` shows only the last part of the name, and
``:role:`title <target>``` shows ``title``.
"""

from __future__ import annotations

import html
import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|attr|data|exc|obj|const):`(?P<text>[^`]+)`")
TITLED = re.compile(r"^(?P<title>.+?)\s*<(?P<target>[^<>]+)>$")


class SphinxRoles(griffe.Extension):
    """Rewrites ``:role:`target``` in every docstring into an optional cross-reference."""

    def on_object(self, *, obj: griffe.Object, loader: griffe.GriffeLoader, **kwargs: Any) -> None:
        _rewrite(obj, loader)

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader, **kwargs: Any) -> None:
        _rewrite(pkg, loader)  # on_object sees the package's members, not the package itself


def _rewrite(obj: griffe.Object, loader: griffe.GriffeLoader) -> None:
    if obj.docstring is not None and ":" in obj.docstring.value:
        obj.docstring.value = ROLE.sub(lambda m: _reference(obj, loader, m["text"]), obj.docstring.value)


def _reference(obj: griffe.Object, loader: griffe.GriffeLoader, text: str) -> str:
    titled = TITLED.match(text)
    if titled:
        title, target = titled["title"], titled["target"]
    else:
        title, target = None, text
    short = target.startswith("~")
    target = target.lstrip("~").removesuffix("()")
    if title is None:
        title = target.rsplit(".", 1)[-1] if short else target
    identifier = _resolve(obj, loader, target)
    return f'<autoref identifier="{html.escape(identifier)}" optional>`{title}`</autoref>'


def _resolve(obj: griffe.Object, loader: griffe.GriffeLoader, target: str) -> str:
    """The full path of ``target`` as seen from ``obj`` (``target`` itself when it does not resolve)."""
    try:
        loader.modules_collection[target]
        return target
    except (KeyError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        pass
    first, _, rest = target.partition(".")
    try:
        base = obj.resolve(first)
    except griffe.NameResolutionError:
        return target
    return f"{base}.{rest}" if rest else base
