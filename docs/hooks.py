"""MkDocs hooks (mkdocs.yml's ``hooks:``): one set of Markdown files that reads right on GitHub and in
the site.

On GitHub the README is the front page and the docs link to the repository's other files with
``../`` paths. In the site the README becomes ``index.md`` and CHANGELOG.md ``changelog.md``, their
``docs/`` links lose that prefix, and every other file a page links to outside ``docs/`` (an example,
a mission, ``benchmarks/README.md``) is copied under ``repo/`` as it is, so ``mkdocs build --strict``
still checks that each link points at something.

>>> retarget("examples/x.py", from_root=True)
'repo/examples/x.py'
>>> retarget("docs/grading.md#gradescope", from_root=True)
'grading.md#gradescope'
>>> retarget("../README.md", from_root=False), retarget("viewer.md", from_root=False)
('index.md', 'viewer.md')
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[1]
#: files of the repository root that are pages of the site, by their name there
ROOT_PAGES = {"README.md": "index.md", "CHANGELOG.md": "changelog.md"}
LINK = re.compile(r"(!?\[[^\]]*\]\()([^)\s]+)(\))")
FENCE = re.compile(r"(```.*?```)", re.S)


class _Copied(File):
    """A repository file outside ``docs/``, copied into the site as it is (never rendered, even
    when it is Markdown: its own links are relative to where it lives in the repository)."""

    def is_documentation_page(self) -> bool:
        return False

    def is_static_page(self) -> bool:
        return True


def retarget(target: str, from_root: bool) -> str:
    """Where a relative link of a page (of the repository root when ``from_root``, else of
    ``docs/``) points in the site."""
    if re.match(r"[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
        return target
    path, _, anchor = target.partition("#")
    anchor = f"#{anchor}" if anchor else ""
    if not from_root:
        if not path.startswith("../"):
            return target
        path = path[3:]
    if path.startswith("docs/"):
        return path[5:] + anchor
    return ROOT_PAGES.get(path, f"repo/{path}") + anchor


def _links(markdown: str) -> list[str]:
    """The link targets of ``markdown``, outside code blocks."""
    return [m.group(2) for chunk in FENCE.split(markdown)[::2] for m in LINK.finditer(chunk)]


def _rewrite(markdown: str, from_root: bool) -> str:
    chunks = FENCE.split(markdown)
    for i in range(0, len(chunks), 2):
        chunks[i] = LINK.sub(lambda m: m.group(1) + retarget(m.group(2), from_root) + m.group(3), chunks[i])
    return "".join(chunks)


def on_files(files: Files, config: Any) -> Files:
    """The root pages as site pages, and every repository file a page links to as a copy."""
    sources: list[tuple[str, bool]] = []
    for name, page in ROOT_PAGES.items():
        text = (ROOT / name).read_text(encoding="utf-8")
        files.append(File.generated(config, page, content=text))
        sources.append((text, True))
    docs = ROOT / "docs"
    sources += [(p.read_text(encoding="utf-8"), False) for p in sorted(docs.glob("*.md"))]
    wanted = {retarget(t, from_root).partition("#")[0] for text, from_root in sources for t in _links(text)}
    for uri in sorted(u for u in wanted if u.startswith("repo/")):
        source = ROOT / uri.removeprefix("repo/")
        if source.is_file() and files.get_file_from_path(uri) is None:
            copied = _Copied(uri, src_dir=None, dest_dir=config["site_dir"], use_directory_urls=False)
            copied.abs_src_path = str(source)
            files.append(copied)
    return files


def on_page_markdown(markdown: str, page: Any, **_: Any) -> str:
    """A page's links as the site has its files."""
    return _rewrite(markdown, from_root=page.file.src_uri in ROOT_PAGES.values())
