"""The grade's results as types: a run's outcome and each criterion's judgement of it, a student's
score on each criterion and variant, the class's summary; what ``grade`` returns, the reports read
and results.json holds (the contract of docs/grading.md).

Inside the grader they are these models, their statuses and codes enums; JSON only at the edges:
:meth:`ClassResults.to_json` is results.json's content, key for key in the contract's order, and
:meth:`ClassResults.from_json` reads it back (``grade --update``), refusing what is not the
contract; a run's message comes through a child's pipe as JSON and is read by
:meth:`RunMessage.from_json` just as strictly.

Example::

    >>> from thymio_bt.run.result import RunStatus
    >>> run = RunRecord(index=0, variant="course", seed=0, robot="course", status=RunStatus.TIMEOUT,
    ...                 code=FailureCode.TIMEOUT, criteria={"stops": Judged(passed=False, feedback="no stop")})
    >>> data = run.to_json()
    >>> data["status"], data["code"], data["criteria"]
    ('TIMEOUT', 'TIMEOUT', {'stops': {'passed': False, 'feedback': 'no stop', 'moment': None, 'where': None}})
    >>> RunRecord.from_json(data) == run, "trajectory" in data    # absent until a picture needs one
    (True, False)
    >>> RunRecord.from_json(data | {"status": "PASSED"})
    Traceback (most recent call last):
    ...
    ValueError: not a run of results.json: status: Input should be 'SUCCESS', 'FAILURE' or 'TIMEOUT'
    >>> RunRecord.from_json(data | {"score": 10})
    Traceback (most recent call last):
    ...
    ValueError: not a run of results.json: score: unknown key 'score'
"""

from __future__ import annotations

import json
from typing import Annotated, Any, ClassVar, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, Field, SerializerFunctionWrapHandler, ValidationError, model_serializer

from thymio_bt.enums import FailureCode, TextEnum
from thymio_bt.grade.assignment import Palette
from thymio_bt.grade.palette import Finding
from thymio_bt.inputs.validation import problems_from
from thymio_bt.run.result import RunStatus


class StudentStatus(TextEnum):
    """A student's ``status`` in results.json."""

    GRADED = "graded"
    #: the file does not load, the folder holds no mission, or it brings plugins the assignment forbids
    INVALID = "invalid"
    #: the grader could not make all the runs
    ERROR = "error"
    #: a signal stopped the grade before all its runs
    INTERRUPTED = "interrupted"


class GraderCode(TextEnum):
    """The grader's own codes of a run the submission broke or could not make (besides the run's
    :class:`~thymio_bt.enums.FailureCode`)."""

    #: over a time or memory limit (or skipped after too many)
    LIMIT = "LIMIT"
    #: the process running it died, or could not start
    CRASH = "CRASH"
    #: the mission cannot run in the variant's world
    WORLD_ERROR = "WORLD_ERROR"


#: a run's ``code``, why it failed: a :class:`FailureCode`, the grader's :class:`GraderCode`, or a
#: plugin behaviour's own code (a string)
RunCode = FailureCode | GraderCode | str


_Part = TypeVar("_Part", bound="_Contract")


class _Contract(BaseModel):
    """A part of results.json: no key that is not the contract's."""

    model_config = ConfigDict(extra="forbid")
    #: what it is, for the message that refuses it
    WHAT: ClassVar[str] = "results.json"
    #: keys left out of the JSON while None (they are added as the grade goes)
    OMITTED: ClassVar[frozenset[str]] = frozenset()

    def to_json(self) -> dict[str, Any]:
        """As results.json holds it."""
        return self.model_dump(mode="json")

    @model_serializer(mode="wrap")
    def _without_omitted(self, dump: SerializerFunctionWrapHandler) -> dict[str, Any]:
        data: dict[str, Any] = dump(self)
        for key in self.OMITTED:
            if key in data and data[key] is None:
                del data[key]
        return data

    @classmethod
    def from_json(cls: type[_Part], data: Any) -> _Part:
        """Read from JSON data, strictly (no number from a string, no key the contract has not): a
        ``ValueError`` saying what is not the contract (its first error)."""
        try:
            text = json.dumps(data, allow_nan=False)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"not {cls.WHAT}: {exc}") from None
        try:
            return cls.model_validate_json(text, strict=True)
        except ValidationError as exc:
            problems = problems_from(exc, data, "", cls)
            more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
            raise ValueError(f"not {cls.WHAT}: {problems[0].path}: {problems[0].message}{more}") from None


class Judged(_Contract):
    """One criterion's judgement of one run."""

    passed: bool
    feedback: str | None = None
    #: when and where it went wrong: ``{t, x, y}``
    moment: dict[str, float] | None = None
    #: ``file:line`` of the node to blame
    where: str | None = None


class RunRecord(_Contract):
    """One run of a student's: how it ended, each criterion's judgement, the commands that make it
    again; the first run of each variant has its ``trajectory`` (``[t, x, y, yaw]`` samples)."""

    WHAT: ClassVar[str] = "a run of results.json"
    OMITTED: ClassVar[frozenset[str]] = frozenset({"spawns", "replay", "trajectory", "reproduce", "check"})

    index: int
    variant: str
    seed: int
    robot: str
    status: RunStatus
    #: None when it did not fail; a known code read back as its enum
    code: Annotated[RunCode | None, Field(union_mode="left_to_right")] = None
    reason: str | None = None
    failed_path: str | None = None
    where: str | None = None
    sim_time: float = 0.0
    final_pose: dict[str, float] | None = None
    collisions: int = 0
    #: the times of the run's spawn events (the picture's jumps); none for a run that did not run
    spawns: list[float] | None = None
    criteria: dict[str, Judged]
    #: the viewer's page data of a failed run (:mod:`.site_replay`): the site's, taken out before results.json
    replay: dict[str, Any] | None = None
    trajectory: list[list[float]] | None = None
    reproduce: str | None = None
    check: str | None = None

    @property
    def broken(self) -> bool:
        """Whether the submission's code broke the run (a limit, a crash, an exception)."""
        return self.code in (GraderCode.LIMIT, GraderCode.CRASH, FailureCode.EXCEPTION)


class RunMessage(RunRecord):
    """A run as a child process sends it to the grader: the run, and its node statistics (for the
    tree's coverage; not in results.json)."""

    WHAT: ClassVar[str] = "a run's message"

    node_stats: dict[str, dict[str, Any]] = {}

    def record(self) -> RunRecord:
        """The run as results.json keeps it."""
        return RunRecord(**{k: v for k, v in self if k != "node_stats"})


class VariantScore(_Contract):
    """A criterion's outcome in one variant: its runs, those passed, the points it earned there and
    the feedback of its first failed run."""

    name: str
    runs: int = 0
    passed_runs: int = 0
    passed: bool = False
    feedback: str | None = None
    earned: float = 0.0


class CriterionScore(_Contract):
    """A criterion's line for one student."""

    name: str
    points: float
    earned: float = 0.0
    passed: bool = False
    runs: int = 0
    passed_runs: int = 0
    variants: list[VariantScore] = []
    #: the first failed run's, with its variant, seed and robot, and how many failed
    feedback: str | None = None
    where: str | None = None


class StudentResult(_Contract):
    """One student's entry of results.json."""

    name: str
    file: str | None = None
    status: StudentStatus
    score: float = 0.0
    max: float
    #: what the palette took off (negative)
    penalty: float = 0.0
    messages: list[str] = []
    criteria: list[CriterionScore] = []
    palette: list[Finding] = []
    #: the tree's coverage over the runs (:meth:`thymio_bt.run.coverage.Coverage.to_json`)
    coverage: dict[str, Any] | None = None
    #: a digest of the tree's shape (:mod:`.similarity`)
    shape: str | None = None
    runs: list[RunRecord] = []


class CriterionInfo(_Contract):
    """A criterion of the assignment, as results.json describes it."""

    name: str
    points: float
    variants: list[str] = []
    pass_rate: float = 1.0
    credit: Literal["shared", "all"] = "shared"
    check: str = ""


class VariantInfo(_Contract):
    """A variant of the assignment, as results.json describes it."""

    name: str
    maze: str | None = None
    start: str | None = None
    robot: str = "course"
    seeds: list[int] = [0]
    noise: bool = False
    visibility: Literal["public", "hidden"] = "public"


class AssignmentInfo(_Contract):
    """What was graded: the assignment's name, file, points, criteria, palette and variants."""

    name: str
    title: str = ""
    file: str = ""
    max: float = 0.0
    criteria: list[CriterionInfo] = []
    palette: Palette = Palette()
    variants: list[VariantInfo] = []


class CriterionRate(_Contract):
    """A criterion's pass rate over the graded students (None when none was graded)."""

    name: str
    pass_rate: float | None


class Summary(_Contract):
    """The class in numbers: students by status, runs, wall time, the mean score, each criterion's
    pass rate, and what confined the students' code."""

    students: int = 0
    graded: int = 0
    invalid: int = 0
    error: int = 0
    interrupted: int = 0
    runs: int = 0
    wall_time: float = 0.0
    mean_score: float | None = None
    criteria: list[CriterionRate] = []
    confinement: str | None = None


class ClassResults(_Contract):
    """A class graded: results.json."""

    assignment: AssignmentInfo
    students: list[StudentResult] = []
    summary: Summary = Summary()
    #: groups of students whose trees have the same shape (the TA's to look at)
    similar: list[list[str]] = []


__all__ = [
    "AssignmentInfo",
    "ClassResults",
    "CriterionInfo",
    "CriterionRate",
    "CriterionScore",
    "GraderCode",
    "Judged",
    "RunCode",
    "RunMessage",
    "RunRecord",
    "StudentResult",
    "StudentStatus",
    "Summary",
    "VariantInfo",
    "VariantScore",
]
