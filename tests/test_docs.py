"""A strict check of the docs, beside ``make docs`` (the MkDocs build with --strict): every
relative link and every path named in backticks resolves, anchors name a heading, and the
docs describe the present."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted([ROOT / "README.md", ROOT / "CHANGELOG.md", *(ROOT / "docs").rglob("*.md")])
#: history belongs in CHANGELOG.md, not in documents that describe current behaviour
HISTORY = (
    "before these changes",
    "this stop",
    "stops ago",
    "recorded on the issue",
    "previous session",
    "this session",
    "same half hour",
)
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)")
#: a repository path in backticks: `docs/x.md`, `src/medax/cad/reader.py`, `benchmarks/`
PATH = re.compile(r"`((?:docs|src|tests|benchmarks)/[\w./-]*)`")


def slug(heading: str) -> str:
    """GitHub's anchor for a heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    text = path.read_text(encoding="utf-8")
    return {slug(h) for h in re.findall(r"^#+\s+(.*)$", text, flags=re.M)}


def ids(paths: list[Path]) -> list[str]:
    return [str(p.relative_to(ROOT)) for p in paths]


def test_docs_exist():
    names = set(ids(DOCS))
    assert {"docs/formats.md", "docs/limitations.md", "docs/benchmarks.md"} <= names


@pytest.mark.parametrize("doc", DOCS, ids=ids(DOCS))
def test_relative_links_resolve(doc):
    text = doc.read_text(encoding="utf-8")
    broken = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):  # http:, https:, mailto:
            continue
        file, _, anchor = target.partition("#")
        dest = (doc.parent / file).resolve() if file else doc
        if not dest.exists():
            broken.append(target)
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(target)
    assert broken == []


@pytest.mark.parametrize("doc", DOCS, ids=ids(DOCS))
def test_named_paths_exist(doc):
    text = doc.read_text(encoding="utf-8")
    missing = sorted({p for p in PATH.findall(text) if not (ROOT / p.rstrip(".")).exists()})
    assert missing == []


PRESENT = [d for d in DOCS if d.name != "CHANGELOG.md"]


@pytest.mark.parametrize("doc", PRESENT, ids=ids(PRESENT))
def test_docs_describe_the_present(doc):
    text = doc.read_text(encoding="utf-8").lower()
    assert [p for p in HISTORY if p in text] == []
