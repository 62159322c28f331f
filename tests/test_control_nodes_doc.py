"""docs/control_nodes.md: each example mission runs, and ends as its '# result:' line says."""

import re
from pathlib import Path

import pytest

from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run

DOC = Path(__file__).resolve().parents[1] / "docs" / "control_nodes.md"
BLOCKS = re.findall(r"```yaml\n# result: (.*?)\n(.*?)```", DOC.read_text(), re.S)
#: the plugins the examples use: (file name, Python source)
PLUGINS = re.findall(r"```python\n# (\w+\.py)\n(.*?)```", DOC.read_text(), re.S)


def test_the_page_has_a_decorator_of_one_s_own_that_a_mission_uses():
    assert [name for name, _ in PLUGINS] == ["at_once.py"]
    assert any("plugins: [at_once.py]" in body for _, body in BLOCKS)


def test_the_page_has_an_example_of_each_control_node_it_explains():
    text = "\n".join(body for _, body in BLOCKS)
    for kind in ("reactive_sequence", "sequence", "selector", "reactive_selector", "parallel", "invert"):
        assert re.search(rf"[ -] {kind}:", text), kind


@pytest.mark.parametrize("result, body", BLOCKS, ids=[re.search(r"name: (\w+)", b).group(1) for _, b in BLOCKS])
def test_control_node_example(tmp_path, result, body):
    path = tmp_path / "example.yaml"
    path.write_text(body)
    for name, source in PLUGINS:
        (tmp_path / name).write_text(source)
    run = Run(load_mission(path)).run()
    status, *rest = result.split()
    assert run.status == status
    if at := re.search(r" at (\S+)", result):
        assert run.failed_path == at.group(1)
    if code := re.search(r"\((COLLISION)\)", result):
        assert run.code == code.group(1)
    assert f"{run.sim_time:.1f} s" in result
    if x := re.search(r"x = ([\d.]+) m", result):
        assert f"{run.final_pose.x:.2f}" == x.group(1)
    if yaw := re.search(r"yaw = ([-\d]+) deg", result):
        assert round(run.final_pose.yaw * 180 / 3.141592653589793) == int(yaw.group(1))
    assert (run.collisions == 0) == ("COLLISION" not in result)
