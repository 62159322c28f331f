"""The docs site's set-up (mkdocs.yml, docs/hooks.py): every page is in the navigation (MkDocs only
mentions an orphan page, even with --strict), the public modules are in the API reference, and the
hooks' link rewriting does what its examples say. CI builds the site itself (.ci/run)."""

import doctest
import importlib.util
import re
from pathlib import Path

import _require
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]


def _nav_pages(nav: object) -> list[str]:
    if isinstance(nav, str):
        return [nav]
    if isinstance(nav, list):
        return [p for item in nav for p in _nav_pages(item)]
    if isinstance(nav, dict):
        return [p for value in nav.values() for p in _nav_pages(value)]
    return []


def test_every_page_is_in_the_navigation():
    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))
    nav = _nav_pages(config["nav"])
    pages = {p.name for p in (ROOT / "docs").glob("*.md")} | {"index.md", "changelog.md"}
    assert sorted(nav) == sorted(pages)


@pytest.mark.parametrize(
    "module",
    [
        "thymio_bt",
        "thymio_bt.testing",
        "thymio_bt.notebook",
        "thymio_bt.errors",
        "thymio_bt.robot.interface",
        "thymio_bt.geometry",
        "thymio_bt.behaviours.base",
        "thymio_bt.inputs.fields",
        "thymio_bt.mission",
        "thymio_bt.run.runner",
        "thymio_bt.run.sweep",
    ],
)
def test_a_public_module_declares_its_api_and_is_in_the_reference(module):
    imported = importlib.import_module(module)
    assert imported.__all__ and all(hasattr(imported, name) for name in imported.__all__)
    api = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    assert re.search(rf"^::: {re.escape(module)}$", api, re.M)


def test_the_hooks_examples():
    _require.module("mkdocs")  # the docs extra, in dev
    spec = importlib.util.spec_from_file_location("docs_hooks", ROOT / "docs" / "hooks.py")
    assert spec and spec.loader
    hooks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hooks)
    failed, attempted = doctest.testmod(hooks)
    assert attempted >= 3 and failed == 0
