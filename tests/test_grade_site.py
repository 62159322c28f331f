"""``grade --html``: the static site written from a results.json (tests/data/grade_results_sample.json,
three students: full marks, points lost with failed runs and a forbidden node, an invalid mission).

Unit tests read the written files (escaping, safe page names, links); the browser tests load every
page in a real headless Chromium, driven over the DevTools protocol on a pipe
(``--remote-debugging-pipe``: no port, no websocket library), and fail on any console error,
uncaught exception, failed or non-local request. Screenshots of the class page and a student page
go to ``$THYMIO_BT_ARTEFACTS`` (else the test's tmp folder). Without Chromium the browser tests skip
locally and fail in CI (tests/_require.py); .ci/setup.d/50-chromium.sh installs it.
"""

from __future__ import annotations

import html
import json
import os
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlparse

import pytest

from thymio_bt.errors import UserError
from thymio_bt.grade.site import most_missed, page_names, safe_name, write_site
from thymio_bt.maze.files import load_maze

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "tests" / "data" / "grade_results_sample.json"
PAYLOAD = '"\'><script>window.__pwned=1</script><i data-pwn="1">&amp;'


def sample() -> dict[str, Any]:
    """The sample results, with the mazes as absolute paths (the tests run from any folder)."""
    results = json.loads(SAMPLE.read_text())
    for variant in results["assignment"]["variants"]:
        variant["maze"] = str(ROOT / variant["maze"])
    return results


class Page(HTMLParser):
    """What a written page holds: its tags, the attributes with links, its text."""

    def __init__(self, path: Path) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.text: list[str] = []
        self.feed(path.read_text(encoding="utf-8"))

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data: str) -> None:
        self.text.append(data)

    def links(self) -> list[str]:
        return [a[k] for _, a in self.tags for k in ("href", "src") if a.get(k)]  # type: ignore[misc]


@pytest.fixture
def site(tmp_path: Path) -> tuple[dict[str, Any], list[Path]]:
    results = sample()
    return results, write_site(results, tmp_path / "site")


def test_every_student_has_a_page_and_the_class_page_comes_first(site, tmp_path):
    results, written = site
    out = tmp_path / "site"
    assert written[0] == out / "index.html"
    assert [p.relative_to(out).as_posix() for p in written[1:]] == [
        f"students/{s['name']}.html" for s in results["students"]
    ]
    assert all(p.is_file() for p in written)
    assert sorted(p for p in out.rglob("*") if p.is_file()) == sorted(written)  # no temporary file left


def test_every_link_resolves_to_a_written_file_and_nothing_is_fetched(site, tmp_path):
    _, written = site
    out = (tmp_path / "site").resolve()
    for path in written:
        page = Page(path)
        assert not [t for t, _ in page.tags if t in ("script", "iframe", "object", "embed")], path
        assert not [a for t, a in page.tags if t == "link" and a.get("rel") != "icon"], path
        for link in page.links():
            url = urlparse(link)
            assert url.scheme in ("", "data"), f"{path.name} links {link}"
            if url.scheme == "data" or not url.path:
                continue
            target = (path.parent / unquote(url.path)).resolve()
            assert target.is_file() and out in target.parents, f"{path.name}: {link} -> {target}"
        assert "url(" not in path.read_text() and "@import" not in path.read_text()
    index_links = Page(written[0]).links()
    assert sum(link.startswith("students/") for link in index_links) == len(written) - 1


def test_the_class_page_shows_the_class(site):
    results, written = site
    text = " ".join(Page(written[0]).text)
    index = written[0].read_text()
    assert index.count('<tr class="student">') == 3
    assert index.count('class="bar-row') == len(results["assignment"]["criteria"])
    # stops, dead end and no collision are each missed by 1 of 2 graded students; fewest runs pass stops
    assert index.count("bar-row worst") == 1
    assert 'bar-row worst" data-criterion="stops 5 cm from the wall"' in index
    assert "Most missed: " in text and "6 / 10" in text  # mean of the graded students (10 and 2)
    assert "2 graded, 1 invalid, 0 error" in text


def test_a_student_page_explains_the_score(site):
    results, written = site
    bob = next(p for p in written if p.name == "bob.html").read_text()
    student = results["students"][1]
    assert bob.count('<tr class="criterion ') == len(student["criteria"])
    assert "stopped 7.0 cm from the wall" in bob and "subs/bob/part1_2.yaml:32" in bob
    assert "WallFollow is not allowed" in bob and "&minus;1" in bob  # the palette's finding
    failed = [
        r for r in student["runs"] if r["status"] != "SUCCESS" or not all(v["passed"] for v in r["criteria"].values())
    ]
    assert bob.count('<tr class="reproduce">') == len(failed) == 4
    assert all(f'<code class="cmd">{r["reproduce"]}</code>' in bob for r in failed)
    # coverage: one row per node, the never-ticked WallFollow greyed and marked
    assert bob.count('<tr class="tree-node') == len(student["coverage"]["nodes"])
    assert bob.count('class="tree-node cov-never"') == 1 and "never ticked</span>" in bob


def test_each_variant_is_drawn_with_its_walls_path_and_failing_moments(site):
    results, written = site
    bob = next(p for p in written if p.name == "bob.html").read_text()
    maze = load_maze(results["assignment"]["variants"][0]["maze"])
    assert bob.count('<svg xmlns="http://www.w3.org/2000/svg" class="trajectory"') == 2
    assert bob.count("<polygon ") == 2 * len(maze.shapes())
    assert bob.count('class="jump"') == 2  # the respawn after part 1 is a jump, not a path through walls
    # course: the stop at 7 cm (both seeds, one mark); shifted: the stop, the collision, the end of the run
    assert bob.count('<g class="fail-mark">') == 1 + 3
    alice = next(p for p in written if p.name == "alice.html").read_text()
    assert alice.count('class="trajectory"') == 2 and '<g class="fail-mark">' not in alice
    assert "All 4 runs ended in SUCCESS" in alice


def test_the_start_is_drawn_from_a_pose_a_text_or_a_spawn_name(tmp_path):
    """The contract's {x, y, yaw}, "x,y,yaw" and the maze's spawn name (part1 is (0.1, 0.1, 0)) put
    the start at the same place; without a start, the path's first sample stands for it."""
    drawn = {}
    for n, start in enumerate(({"x": 0.1, "y": 0.1, "yaw": 0.0}, "0.1,0.1,0", "part1", None, "nowhere")):
        results = sample()
        for variant in results["assignment"]["variants"]:
            variant["start"] = start
        written = write_site(results, tmp_path / f"site{n}")
        alice = next(p for p in written if p.name == "alice.html").read_text()
        drawn[str(start)] = re.findall(r"<title>start pose</title><circle cx=\"([\d.]+)\" cy=\"([\d.]+)\"", alice)
    assert len(drawn["part1"]) == 2  # one per variant
    assert drawn[str({"x": 0.1, "y": 0.1, "yaw": 0.0})] == drawn["0.1,0.1,0"] == drawn["part1"]
    assert drawn["None"][0] == drawn["part1"][0]  # the course variant's path starts at part1
    assert drawn["nowhere"] == drawn["None"]


def test_seeds_that_miss_a_criterion_at_nearly_the_same_place_share_a_mark(tmp_path):
    results = sample()
    bob = results["students"][1]
    moment = bob["runs"][1]["criteria"]["stops 5 cm from the wall"]["moment"]
    moment["x"] += 0.02  # seed 1 stopped 2 cm further: still the same mark
    written = write_site(results, tmp_path / "site")
    page = next(p for p in written if p.name == "bob.html").read_text()
    assert page.count('<g class="fail-mark">') == 1 + 3 and "(seeds 0, 1)" in page
    moment["x"] += 0.05  # 7 cm further: a mark of its own
    written = write_site(results, tmp_path / "site2")
    page = next(p for p in written if p.name == "bob.html").read_text()
    assert page.count('<g class="fail-mark">') == 2 + 3


def test_an_invalid_students_page_says_why(site):
    results, written = site
    carol = next(p for p in written if p.name == "carol.html").read_text()
    assert 'id="messages"' in carol and "was not graded" in carol
    for message in results["students"][2]["messages"]:
        assert message.replace("'", "&#x27;") in carol
    assert "<svg" not in carol


def _poison(value: Any, keys: bool = False) -> Any:
    """Every text of ``value`` with markup appended; the keys too with ``keys`` (the keys that are
    names: a run's criteria, a node's ended_by)."""
    if isinstance(value, str):
        return value + PAYLOAD
    if isinstance(value, list):
        return [_poison(v) for v in value]
    if isinstance(value, dict):
        return {
            (_poison(k) if keys else k): _poison(v, keys=k in ("criteria", "ended_by") and isinstance(v, dict))
            for k, v in value.items()
        }
    return value


def test_every_text_from_the_results_is_escaped(tmp_path):
    results = _poison(sample())
    results["students"][0]["name"] = '<script>alert("x")</script>'
    written = write_site(results, tmp_path / "site")
    for path in written:
        page = Page(path)
        assert not [t for t, _ in page.tags if t == "script"], path
        assert not [a for _, a in page.tags if "data-pwn" in a], path
        assert PAYLOAD in "".join(page.text), path  # shown as text
    assert "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt;" in written[0].read_text()
    assert (tmp_path / "site" / "students" / "script_alert_x_script.html").is_file()


@pytest.mark.parametrize(
    "name", ["../x", "../../etc/passwd", "/etc/passwd", "..", ".", "", "a/b\\c", "~root", ".hidden", "x" * 300, "é"]
)
def test_page_names_stay_inside_the_site(tmp_path, name):
    out = tmp_path / "site"
    results = {"assignment": {"name": "a"}, "students": [{"name": name, "status": "graded"}]}
    written = write_site(results, out)
    page = written[1]
    assert page.resolve().parent == (out / "students").resolve()
    assert page.name == f"{safe_name(name)}.html" and not page.name.startswith(".")
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file()) == sorted(
        p.relative_to(tmp_path) for p in written
    )


def test_page_names_are_unique_even_on_a_case_blind_file_system():
    names = page_names([{"name": n} for n in ("Bob", "bob", "bob", "b/o/b", "b o b", "b_o_b")])
    assert names == ["Bob", "bob-2", "bob-3", "b_o_b", "b_o_b-2", "b_o_b-3"]
    assert len({n.casefold() for n in names}) == len(names)


def test_the_most_missed_criterion_breaks_ties_on_runs():
    stats = [
        {"name": "a", "students": 4, "passed": 2, "run_rate": 0.75},
        {"name": "b", "students": 4, "passed": 2, "run_rate": 0.5},
        {"name": "c", "students": 4, "passed": 3, "run_rate": 0.1},
    ]
    assert most_missed(stats) == "b"
    assert most_missed([{"name": "a", "students": 2, "passed": 2, "run_rate": 1.0}]) is None


def test_a_maze_that_cannot_be_read_leaves_the_path_without_walls(tmp_path):
    results = sample()
    for variant in results["assignment"]["variants"]:
        variant["maze"] = str(tmp_path / "gone.yaml")
    written = write_site(results, tmp_path / "site")
    bob = next(p for p in written if p.name == "bob.html").read_text()
    assert "<polygon " not in bob and bob.count('class="path"') >= 2 and "could not be read" in bob


def test_a_relative_maze_is_found_from_the_project_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    written = write_site(json.loads(SAMPLE.read_text()), tmp_path / "site")
    assert "<polygon " in next(p for p in written if p.name == "bob.html").read_text()


def test_a_file_in_the_way_is_a_user_error(tmp_path):
    (tmp_path / "site").write_text("not a folder")
    with pytest.raises(UserError, match="not a folder"):
        write_site(sample(), tmp_path / "site")


# ---------------------------------------------------------------- the pages in a real browser


@pytest.fixture
def artefacts(tmp_path) -> Path:
    folder = Path(os.environ["THYMIO_BT_ARTEFACTS"]) if os.environ.get("THYMIO_BT_ARTEFACTS") else tmp_path
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def test_the_browser_check_sees_errors_and_requests(browser, tmp_path):
    """The check the site must pass can fail: a thrown error, console.error, a missing file and a
    request to the network are each caught."""
    page = tmp_path / "broken.html"
    page.write_text(
        "<!doctype html><html><head><title>broken</title></head><body><p>broken</p>"
        "<script>console.error('deliberate console error');</script>"
        "<script>throw new Error('deliberate exception');</script>"
        '<img src="missing.png"><img src="http://127.0.0.1:9/off-the-machine.png"></body></html>'
    )
    tab = browser.open(page.as_uri())
    problems = "\n".join(tab.problems())
    tab.close()
    assert "deliberate console error" in problems
    assert "deliberate exception" in problems
    assert "missing.png" in problems
    assert "request off the machine's files: http://127.0.0.1:9/off-the-machine.png" in problems
    blocked = tmp_path / "blocked.html"  # what the site's own Content-Security-Policy would refuse
    blocked.write_text(
        '<!doctype html><html><head><meta http-equiv="Content-Security-Policy" content="default-src \'none\'">'
        "<title>blocked</title></head><body><p style='color: red'>styled</p></body></html>"
    )
    tab = browser.open(blocked.as_uri())
    assert "Content Security Policy" in "\n".join(tab.problems())
    tab.close()
    clean = tmp_path / "clean.html"
    clean.write_text("<!doctype html><title>clean</title><p>fine</p>")
    tab = browser.open(clean.as_uri())
    assert tab.problems() == []
    tab.close()


def test_every_page_loads_cleanly_in_chromium(browser, site, tmp_path, artefacts):
    results, written = site
    index, *pages = written
    tab = browser.open(index.as_uri())
    assert tab.problems() == []
    dom = tab.evaluate(
        """({
        title: document.title,
        rows: document.querySelectorAll('#students tbody tr').length,
        bars: document.querySelectorAll('#criteria-bars .bar-row').length,
        worst: [...document.querySelectorAll('.bar-row.worst')].map(e => e.dataset.criterion),
        links: [...document.querySelectorAll('#students a')].map(a => a.href),
        overflow: document.documentElement.scrollWidth > window.innerWidth,
        scripts: document.scripts.length,
        })"""
    )
    assert dom["rows"] == len(results["students"]) == 3
    assert dom["bars"] == len(results["assignment"]["criteria"])
    assert dom["worst"] == ["stops 5 cm from the wall"]
    assert [Path(unquote(urlparse(link).path)) for link in dom["links"]] == pages
    assert not dom["overflow"] and dom["scripts"] == 0
    shots = [tab.screenshot(artefacts / "grade_site_index.png")]
    tab.close()
    for student, page in zip(results["students"], pages, strict=True):
        tab = browser.open(page.as_uri())
        assert tab.problems() == [], page.name
        dom = tab.evaluate(
            """({
            name: document.querySelector('h1').textContent,
            criteria: document.querySelectorAll('#criteria tbody tr').length,
            svgs: [...document.querySelectorAll('svg.trajectory')].map(s => ({
                width: s.getBoundingClientRect().width, walls: s.querySelectorAll('.walls polygon').length,
                paths: s.querySelectorAll('polyline.path').length})),
            messages: document.querySelectorAll('#messages li').length,
            back: document.querySelector('a.back, .back a').href,
            overflow: document.documentElement.scrollWidth > window.innerWidth,
            })"""
        )
        assert dom["name"] == student["name"]
        assert dom["criteria"] == len(student["criteria"])
        assert dom["messages"] == len(student["messages"])
        assert Path(unquote(urlparse(dom["back"]).path)) == index
        assert not dom["overflow"], page.name
        if student["runs"]:
            assert len(dom["svgs"]) == 2
            assert all(s["width"] > 200 and s["walls"] > 0 and s["paths"] >= 1 for s in dom["svgs"])
        else:
            assert dom["svgs"] == []
        if student["name"] == "bob":
            shots.append(tab.screenshot(artefacts / "grade_site_student_bob.png"))
        tab.close()
    for shot in shots:
        assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 10_000


@pytest.mark.slow  # grading the class: 3-10 s
def test_a_real_grading_of_the_example_class_loads_cleanly(browser, tmp_path):
    """What ``thymio-bt grade --html`` writes for the example class (the grader's own results, not
    the sample) passes the same browser check, with a page and a picture per variant for each student."""
    site = tmp_path / "site"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "thymio_bt",
            "grade",
            "assignments/course_part1_2.yaml",
            *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "examples" / "class").iterdir()),
            "--html",
            str(site),
            "--out",
            str(tmp_path / "results.json"),
            "--workers",
            "2",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode in (0, 1), done.stderr
    results = json.loads((tmp_path / "results.json").read_text())
    pages = sorted((site / "students").glob("*.html"))
    assert len(pages) == len(results["students"]) >= 2
    tab = browser.open((site / "index.html").as_uri())
    assert tab.problems() == []
    assert tab.evaluate("document.querySelectorAll('#students tbody tr').length") == len(results["students"])
    tab.close()
    variants = len(results["assignment"]["variants"])
    for page, student in zip(pages, sorted(results["students"], key=lambda s: s["name"]), strict=True):
        tab = browser.open(page.as_uri())
        assert tab.problems() == [], page.name
        dom = tab.evaluate(
            "({svgs: document.querySelectorAll('svg.trajectory .walls').length,"
            " criteria: document.querySelectorAll('#criteria tbody tr').length,"
            " overflow: document.documentElement.scrollWidth > window.innerWidth})"
        )
        assert dom == {
            "svgs": variants if student["runs"] else 0,
            "criteria": len(student["criteria"]),
            "overflow": False,
        }, page.name
        tab.close()
        text = page.read_text()
        assert all(text.count(html.escape(m)) == 1 for m in student["messages"]), page.name  # said once


def test_a_hostile_class_runs_nothing_in_chromium(browser, tmp_path):
    results = _poison(sample())
    results["students"][0]["name"] = "<script>window.__pwned=1</script>"
    for page in write_site(results, tmp_path / "site"):
        tab = browser.open(page.as_uri())
        assert tab.problems() == [], page.name
        dom = tab.evaluate(
            "({pwned: window.__pwned === 1, scripts: document.scripts.length,"
            " injected: document.querySelectorAll('[data-pwn]').length})"
        )
        assert dom == {"pwned": False, "scripts": 0, "injected": 0}, page.name
        tab.close()


def test_the_sample_follows_the_contract():
    """The sample is what ``thymio-bt grade`` writes: the contract's keys, a trajectory (at most 300
    samples) on the first run of each variant only."""
    results = json.loads(SAMPLE.read_text())
    assert set(results) == {"assignment", "students", "summary"}
    assert [s["status"] for s in results["students"]] == ["graded", "graded", "invalid"]
    keys = {"name", "file", "status", "score", "max", "messages", "criteria", "palette", "coverage", "runs"}
    run_keys = {
        "variant",
        "seed",
        "robot",
        "status",
        "code",
        "reason",
        "failed_path",
        "where",
        "sim_time",
        "final_pose",
        "collisions",
        "criteria",
        "reproduce",
    }
    for student in results["students"]:
        assert set(student) == keys
        assert student["score"] == sum(c["earned"] for c in student["criteria"]) - sum(
            p["points"] for p in student["palette"]
        )
        traced = [(r["variant"], r["seed"]) for r in student["runs"] if "trajectory" in r]
        assert len(traced) == len({v for v, _ in traced}) == (2 if student["runs"] else 0)
        for run in student["runs"]:
            assert set(run) - {"trajectory"} == run_keys
            assert len(run.get("trajectory", [])) <= 300
    bob = results["students"][1]
    assert bob["score"] < bob["max"] and bob["palette"] and any(r["status"] == "FAILURE" for r in bob["runs"])
