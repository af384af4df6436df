"""Figures a bench writes into the docs, between the markers `<!-- NAME: … -->` and `<!-- /NAME -->`
that say which script wrote them: rerunning it with `--write` replaces what is between them."""

from __future__ import annotations

import re
from pathlib import Path


def write_marked(path: Path, name: str, text: str) -> None:
    """`text` between the `name` markers of the file at `path`; SystemExit when it has none."""
    marked = re.compile(rf"(<!-- {re.escape(name)}: .*? -->\n).*?(<!-- /{re.escape(name)} -->)", re.S)
    written, count = marked.subn(lambda m: m.group(1) + text + "\n" + m.group(2), path.read_text())
    if count != 1:
        raise SystemExit(f"{path.name} has no {name} markers")
    path.write_text(written)
