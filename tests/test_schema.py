"""The JSON Schema of missions: valid, up to date, accepts the course's missions, rejects mistakes.

Editors (yaml-language-server) use it to complete and check missions as they are typed, so it must
accept every real mission and flag the mistakes it can see without loading anything: unknown keys
and parameters, wrong types, values outside a fixed set. (A misspelt behaviour name cannot be told
apart from a subtree defined in an included file, so only the loader reports those.)
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import jsonschema
import pytest
import yaml
from click.testing import CliRunner

from thymio_bt.analysis.schema import mission_schema
from thymio_bt.cli import main
from thymio_bt.mission import load_mission
from thymio_bt.mission.assemble import INCLUDE_KEYS

ROOT = Path(__file__).resolve().parents[1]
SCHEMA_FILE = ROOT / "schema" / "mission.schema.json"
BROKEN = ROOT / "tests" / "broken"
HEADER = "# yaml-language-server: $schema=../schema/mission.schema.json"
MISSIONS = sorted((ROOT / "missions").glob("*.yaml"))
LIBRARIES = sorted((ROOT / "missions" / "lib").glob("*.yaml"))

#: Broken files whose mistake the schema sees, and the edits that fix them (so each test also
#: proves that it is that mistake, and nothing else in the file, that the schema rejects).
FIXES: dict[str, list[tuple[str, str]]] = {
    "typo_parameter.yaml": [("distanse:", "distance:")],
    "extra_parameter.yaml": [("    colour: red\n", "")],
    "typo_top_key.yaml": [("parameter:", "parameters:")],
    "typo_composite.yaml": [("sequense:", "sequence:")],
    "timeout_unknown_key.yaml": [("    secnds: 5\n", "")],
    "wrong_type_list.yaml": [("[1, 2]", "0.1")],
    "wrong_type_bool.yaml": [("maybe", "true")],
    "wrong_type_choice.yaml": [("front_centre", "front_center")],
    "parallel_bad_policy.yaml": [("success_on_some", "success_on_one")],
    "repeat_bad_times.yaml": [("times: 0", "times: 2")],
    "retry_without_times.yaml": [
        ("retry: {MoveDistance: {distance: 5cm}}", "retry: {times: 2, do: {MoveDistance: {distance: 5cm}}}")
    ],
    "node_with_two_keys.yaml": [("      TurnAngle:", "    - TurnAngle:")],
    "empty_children.yaml": [("children: []", "children: [Stop]")],
    "parameter_is_a_list.yaml": [("[10cm/s]", "10cm/s")],
    "missing_tree.yaml": [("start: part1\n", "start: part1\ntree: Stop\n")],
    "missing_maze.yaml": [("start:", "maze: two_parts_maze\nstart:")],
    "bad_settings.yaml": [("seed: -3", "seed: 3"), ("wheels", "wheel"), ("10 cm", "10 s")],
}


@pytest.fixture(scope="module")
def schema() -> dict[str, Any]:
    return mission_schema()


@pytest.fixture(scope="module")
def validator(schema: dict[str, Any]) -> jsonschema.protocols.Validator:
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _is_mission(data: Any) -> bool:
    return isinstance(data, dict) and "tree" in data


def test_the_committed_schema_is_the_generated_one(schema: dict[str, Any]) -> None:
    # regenerate with: thymio-bt schema -o schema/mission.schema.json
    assert json.loads(SCHEMA_FILE.read_text(encoding="utf-8")) == schema
    assert SCHEMA_FILE.read_text(encoding="utf-8") == json.dumps(schema, indent=1) + "\n"


def test_the_schema_command_prints_the_committed_file() -> None:
    result = CliRunner().invoke(main, ["schema"])
    assert result.exit_code == 0, result.output
    assert result.stdout == SCHEMA_FILE.read_text(encoding="utf-8")


def test_the_schema_command_writes_the_committed_file(tmp_path: Path) -> None:
    out = tmp_path / "mission.schema.json"
    result = CliRunner().invoke(main, ["schema", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_text(encoding="utf-8") == SCHEMA_FILE.read_text(encoding="utf-8")


def test_the_schema_knows_every_behaviour_composite_and_decorator(schema: dict[str, Any]) -> None:
    node_names = set(schema["$defs"]["node"]["anyOf"][1]["properties"])
    assert {
        "MoveUntilWall",
        "TurnAngle",
        "WallFollow",
        "sequence",
        "reactive_selector",
        "parallel",
        "repeat",
        "timeout",
        "guard",
        "one_shot",
    } <= node_names


def _errors(validator: jsonschema.protocols.Validator, data: Any) -> list[str]:
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in validator.iter_errors(data)]


@pytest.mark.parametrize("path", MISSIONS + LIBRARIES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_mission_is_valid_against_the_schema(
    path: Path, schema: dict[str, Any], validator: jsonschema.protocols.Validator
) -> None:
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    if _is_mission(data):
        assert _errors(validator, data) == []
    else:
        # a library of subtrees (include:): the mission schema's parts that an included file may hold
        assert path in LIBRARIES, f"{path} has no tree"
        library = {**schema, "required": [], "properties": {k: schema["properties"][k] for k in INCLUDE_KEYS}}
        assert _errors(jsonschema.Draft202012Validator(library), data) == []
        assert data["subtrees"]


def test_the_missions_are_checked() -> None:
    assert len(MISSIONS) >= 5 and all(_is_mission(yaml.safe_load(p.read_text())) for p in MISSIONS)


@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.name)
def test_every_mission_names_the_schema_on_its_first_line(path: Path) -> None:
    assert path.read_text(encoding="utf-8").split("\n", 1)[0] == HEADER


@pytest.mark.parametrize("name", sorted(FIXES))
def test_the_schema_rejects_a_broken_mission_and_accepts_it_fixed(
    name: str, tmp_path: Path, validator: jsonschema.protocols.Validator
) -> None:
    broken = (BROKEN / name).read_text(encoding="utf-8")
    assert not validator.is_valid(yaml.safe_load(broken)), f"the schema accepts {name}"
    fixed = broken
    for old, new in FIXES[name]:
        assert old in fixed, f"{name}: the fix {old!r} no longer applies"
        fixed = fixed.replace(old, new)
    errors = [e.message for e in validator.iter_errors(yaml.safe_load(fixed))]
    assert errors == [], f"{name} fixed is still rejected"
    path = tmp_path / name
    path.write_text("\n".join(line for line in fixed.split("\n") if not line.startswith("# expect")))
    load_mission(path)  # and the loader agrees that the fix was the only problem
