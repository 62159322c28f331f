"""Which file each student handed in: a SUBMISSION argument is a mission file (the student is its
name without suffix) or a folder (the student is the folder's name; the mission is the file the
assignment names, else the only mission file in it).

A folder without a usable mission is the student's problem, not the grader's: it comes back with
its message, to be graded ``invalid``. A path that does not exist is the grader's typo: an error.

Example::

    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp())
    >>> (root / "ada").mkdir(); _ = (root / "ada" / "part1_2.yaml").write_text("name: x")
    >>> (root / "bob").mkdir()
    >>> [(s.name, s.file and s.file.name, s.problem) for s in find_submissions([root / "ada", root / "bob"], None)]
    [('ada', 'part1_2.yaml', None), ('bob', None, 'no mission file (.yaml or .xml) in bob')]
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from thymio_bt.errors import Problem, UserError

#: the suffixes of mission files
MISSION_SUFFIXES = (".yaml", ".yml", ".xml")


@dataclass(frozen=True)
class Submission:
    """A student and the mission file they handed in (None, with the ``problem``, when unusable)."""

    name: str
    file: Path | None
    problem: str | None = None
    #: the student's folder, for a folder submission (its plugins' process gets a copy of it)
    folder: Path | None = None


def find_submissions(paths: Sequence[str | Path], expected: str | None) -> list[Submission]:
    """The submissions the command line names, in its order; ``expected`` is the assignment's
    ``submission:`` file name."""
    found = []
    for ref in paths:
        path = Path(ref)
        if path.is_dir():
            found.append(_in_folder(path, expected))
        elif path.is_file():
            found.append(Submission(path.stem, path))
        else:
            raise UserError(Problem(f"submission not found: {path}", hint="give mission files or folders (subs/*)"))
    names = [s.name for s in found]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise UserError(
            Problem(
                f"two submissions have the same student name: {', '.join(twice)}",
                hint="give each student a folder of their own (subs/NAME/...)",
            )
        )
    return found


def _in_folder(folder: Path, expected: str | None) -> Submission:
    name = folder.resolve().name
    if expected is not None:
        file = folder / expected
        if file.is_file():
            return Submission(name, file, folder=folder)
    missions = sorted(p for p in folder.iterdir() if p.suffix.lower() in MISSION_SUFFIXES and p.is_file())
    if len(missions) == 1:
        return Submission(name, missions[0], folder=folder)
    wanted = f"no {expected}, nor any" if expected else "no"
    if not missions:
        return Submission(name, None, f"{wanted} mission file (.yaml or .xml) in {folder.name}")
    listed = ", ".join(p.name for p in missions)
    return Submission(
        name, None, f"no {expected or 'single mission file'} in {folder.name}, but {len(missions)}: {listed}"
    )
