"""CI runs the test files two at a time (``pytest -n 2``, pytest-xdist, each file whole in one worker:
docs/development.md); conftest starts the longest files first, so that none of them starts last and
keeps one worker busy after the other has finished."""

import subprocess
import sys
from pathlib import Path

from conftest import LONGEST

TESTS = Path(__file__).resolve().parent


def test_the_longest_files_are_test_files_named_once():
    assert len(set(LONGEST)) == len(LONGEST)
    assert all((TESTS / name).is_file() for name in LONGEST), [n for n in LONGEST if not (TESTS / n).is_file()]


def test_the_longest_files_are_collected_first_in_their_order():
    named = ["test_layers.py", "test_places.py", "test_side_by_side.py", "test_playground_missions.py"]
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-p", "no:cacheprovider", *named],
        cwd=TESTS,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    files = list(dict.fromkeys(Path(line.split("::")[0]).name for line in done.stdout.splitlines() if "::" in line))
    assert files == ["test_playground_missions.py", "test_places.py", "test_layers.py", "test_side_by_side.py"]
