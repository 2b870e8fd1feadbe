"""MkDocs hooks: the README becomes the home page, CHANGELOG.md and LICENSE pages too; the
Sphinx roles left in docstrings render as plain code.

The root files live where GitHub and PyPI show them, outside ``docs/``; ``on_files`` adds them
to the build and ``on_page_markdown`` rewrites the links between them and ``docs/``, written
for GitHub, to the site's pages. Nothing is copied into ``docs/``. Docstrings cite names with
mkdocstrings cross-references (``[f][medax.x.f]``, checked by the strict build); the modules
not converted yet (``medax.cad.simplify``) still use Sphinx roles (``:func:`~medax.x.f```),
which Markdown renders as ``:func:`` followed by code: ``on_page_content`` drops the role and,
after ``~``, the module path.
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
#: links of the root files (README, CHANGELOG) relative to the root -> to the site's pages
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


#: ``:func:<code>~a.b.f</code>`` as rendered -> ``<code>f</code>``
ROLE = re.compile(r":(?:func|class|mod|meth|attr|data|exc|obj):<code>(~?)([^<]*)</code>")


def on_page_content(html: str, page: Any, config: Any, files: Files) -> str:
    def code(m: re.Match[str]) -> str:
        name = m.group(2).lstrip(".")
        return f"<code>{name.rsplit('.', 1)[-1] if m.group(1) else name}</code>"

    return ROLE.sub(code, html)


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    uri = page.file.src_uri
    if uri in ("index.md", "changelog.md"):
        for pattern, repl in LINKS:
            markdown = pattern.sub(repl, markdown)
        return markdown
    # a page of docs/ linking to a root file: ../README.md from docs/x.md -> index.md
    up = "../" * (uri.count("/") + 1)
    for name, (target, _) in PAGES.items():
        markdown = markdown.replace(f"]({up}{name}", f"]({up[3:]}{target}")
    return markdown
