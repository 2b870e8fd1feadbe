"""A strict check of the docs, beside ``make docs`` (the MkDocs build with --strict): every
relative link and every path named in backticks resolves, anchors name a heading, and the
docs describe the present."""

import functools
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


# --- API reference: the docstrings docs/reference/*.md renders are numpydoc, without Sphinx roles

#: a Sphinx role renders as plain text in mkdocstrings: cross-references are [name][medax.x.name]
SPHINX_ROLE = re.compile(r":(?:func|class|mod|meth|attr|data|exc|obj):`")
#: documented objects whose docstrings live under src/medax/cad/simplify/, not converted yet
ROLES_PENDING: set[str] = set()
DIRECTIVE = re.compile(r"^::: ([\w.]+)\n((?:[ \t]+.*\n)*)", re.M)


def reference_directives() -> list[tuple[str, list[str] | None]]:
    """``(object path, members option or None)`` of every ``::: object`` in docs/reference/."""
    out = []
    for page in sorted((ROOT / "docs" / "reference").glob("*.md")):
        for name, options in DIRECTIVE.findall(page.read_text(encoding="utf-8")):
            found = re.search(r"members:\s*\[([^\]]*)\]", options)
            members = [m.strip() for m in found.group(1).split(",")] if found else None
            out.append((name, members))
    return out


def rendered_objects(obj, members: list[str] | None = None):
    """``obj`` and its public members, as mkdocstrings renders them (members named ``_x`` are
    filtered out, imported names are not rendered unless listed in ``members``)."""
    yield obj
    for name, member in obj.members.items():
        if name.startswith("_") or (members is not None and name not in members):
            continue
        if member.is_alias and members is None:
            continue
        yield from rendered_objects(member.final_target if member.is_alias else member)


def rendered_docstrings(obj, members: list[str] | None = None):
    """``(path, docstring)`` of the rendered objects that have a docstring."""
    for o in rendered_objects(obj, members):
        if o.docstring is not None:
            yield o.path, o.docstring.value


REFERENCE = reference_directives()


@functools.cache
def api():
    """The package as griffe (mkdocstrings' loader) reads it, without importing it."""
    griffe = pytest.importorskip("griffe")
    loader = griffe.GriffeLoader(search_paths=[str(ROOT / "src")])
    loader.load("medax")
    return loader.modules_collection


def test_reference_lists_the_api():
    names = {name for name, _ in REFERENCE}
    assert {"medax.errors", "medax.trace_axis", "medax.cad.reader", "medax.viz.view3d"} <= names


@pytest.mark.parametrize("name,members", REFERENCE, ids=[n for n, _ in REFERENCE])
def test_reference_docstrings_have_no_sphinx_roles(name, members):
    if name in ROLES_PENDING:
        pytest.skip(f"{name}: docstrings under src/medax/cad/simplify/ not converted yet")
    obj = api()[name]
    obj = obj.final_target if obj.is_alias else obj
    docs = list(rendered_docstrings(obj, members))
    assert docs, f"{name}: nothing rendered"
    assert [path for path, text in docs if SPHINX_ROLE.search(text)] == []


@pytest.mark.parametrize("name,members", REFERENCE, ids=[n for n, _ in REFERENCE])
def test_reference_functions_document_their_parameters(name, members):
    """numpydoc: a rendered function or method that takes arguments has a ``Parameters``
    section naming exactly its arguments."""
    if name in ROLES_PENDING:
        pytest.skip(f"{name}: docstrings under src/medax/cad/simplify/ not converted yet")
    obj = api()[name]
    obj = obj.final_target if obj.is_alias else obj
    wrong = []
    for fn in rendered_objects(obj, members):
        if fn.kind.value != "function" or fn.docstring is None:
            continue
        params = list(fn.parameters)
        if fn.parent.kind.value == "class" and "staticmethod" not in fn.labels:
            params = params[1:]  # self, or cls of a classmethod
        args = {p.name for p in params}
        sections = fn.docstring.parse("numpy", warnings=False)
        named = {
            p.name.lstrip("*") for s in sections if s.kind.value == "parameters" for p in s.value
        }
        if named != args:
            wrong.append(f"{fn.path}: documents {sorted(named)}, takes {sorted(args)}")
    assert wrong == []


def test_sphinx_role_pattern():
    assert SPHINX_ROLE.search("see :func:`~medax.trace_axis` and") is not None
    assert SPHINX_ROLE.search("see [trace_axis][medax.trace_axis] and `a:b`") is None


def docs_command() -> list[str]:
    """The command of ``make docs``, without the venv's bin folder."""
    recipe = re.search(r"^docs:.*\n\t(.*)$", (ROOT / "Makefile").read_text(), flags=re.M)
    assert recipe is not None, "Makefile: no docs target"
    return recipe.group(1).replace("$(BIN)/", "").split()


def test_docs_build_fails_on_a_broken_reference(tmp_path):
    """``make docs`` fails on a cross-reference that resolves nowhere, naming it (``--quiet``
    would hide the warning from ``--strict``); ``make docs`` itself builds the tree as it is."""
    pytest.importorskip("mkdocstrings")
    import shutil
    import subprocess
    import sys

    command = docs_command()
    assert command[:3] == ["mkdocs", "build", "--strict"] and "--quiet" not in command
    shutil.copytree(ROOT / "src", tmp_path / "src", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "mkdocs.yml", tmp_path)
    (tmp_path / "docs").symlink_to(ROOT / "docs")
    errors = tmp_path / "src" / "medax" / "errors.py"
    good = errors.read_text(encoding="utf-8")
    assert '"""Root of all medax errors."""' in good
    bad = good.replace("Root of all medax errors.", "Root of all [errors][medax.no_such_name].")
    errors.write_text(bad, encoding="utf-8")
    run = [sys.executable, "-m", *command, "--site-dir", str(tmp_path / "site")]
    out = subprocess.run(run, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert out.returncode != 0
    assert "Could not find cross-reference target 'medax.no_such_name'" in out.stderr
