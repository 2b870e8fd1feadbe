"""MkDocs hook: the README becomes the home page, CHANGELOG.md and LICENSE pages too.

They live at the repository's root (where GitHub and PyPI show them), outside ``docs/``; this
hook adds them to the build and rewrites the README's links, written relative to the root,
to the site's pages. Nothing is copied into ``docs/``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[1]
#: root file -> (page in the site, wrapper of its text)
PAGES = {
    "README.md": ("index.md", "{}"),
    "CHANGELOG.md": ("changelog.md", "{}"),
    "LICENSE": ("licence.md", "# Licence\n\n```text\n{}```\n"),
}
#: README links relative to the root -> relative to the site's pages
LINKS = [
    (re.compile(r"\]\(docs/algorithms/\)"), "](algorithms/axis.md)"),
    (re.compile(r"\]\(docs/"), "]("),
    (re.compile(r"\]\(CHANGELOG\.md"), "](changelog.md"),
    (re.compile(r"\]\(LICENSE\)"), "](licence.md)"),
]


def on_files(files: Files, config: Any) -> Files:
    for name, (page, wrap) in PAGES.items():
        text = wrap.format((ROOT / name).read_text(encoding="utf-8"))
        files.append(File.generated(config, page, content=text))
    return files


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    if page.file.src_uri == "index.md":
        for pattern, repl in LINKS:
            markdown = pattern.sub(repl, markdown)
    return markdown
