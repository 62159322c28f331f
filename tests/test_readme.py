"""The README's example tests are real: each ```python block that defines test functions is run."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCKS = [b for b in re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S) if "def test_" in b]


def test_the_readme_has_example_tests():
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize("block", BLOCKS, ids=lambda b: re.search(r"def (test_\w+)", b).group(1))
def test_readme_example(block, monkeypatch):
    monkeypatch.chdir(ROOT)  # the README's examples name missions/... as a reader in the checkout types them
    namespace: dict = {}
    exec(compile(block, "README.md", "exec"), namespace)
    tests = [f for name, f in namespace.items() if name.startswith("test_") and callable(f)]
    assert tests
    for test in tests:
        test()
