"""Regenerate the pictures the README shows: ``python docs/make_images.py`` from the repository root.

Each picture is made from a real run of a mission in missions/, exactly as ``thymio-bt run MISSION
--plot ... --gif ...`` would make it; nothing is drawn by hand. Needs the viz extra (matplotlib, pillow).
"""

from __future__ import annotations

from pathlib import Path

from thymio_bt.logs.recording import Recorder
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
from thymio_bt.viz import animation, plots

IMAGES = Path(__file__).parent / "images"

#: mission file -> (path plot, signals plot, animation, animation speed-up)
PICTURES = {
    "missions/course_full.yaml": ("course_full_path.png", None, "course_full.gif", 12.0),
    "missions/maze_part1_2.yaml": (None, "maze_part1_2_signals.png", None, 0.0),
    "missions/waypoints_obstacles.yaml": ("waypoints_obstacles_path.png", None, None, 0.0),
    "missions/maze_6x6_left.yaml": ("maze_6x6_left_path.png", None, None, 0.0),
}


def main() -> None:
    IMAGES.mkdir(exist_ok=True)
    for mission_file, (path_png, signals_png, gif, speedup) in PICTURES.items():
        run = Run(load_mission(mission_file))
        recorder = Recorder(keep=True)
        result = run.run(on_tick=recorder)
        recording = recorder.finish(result)
        print(f"{mission_file}: {result.status} after {result.sim_time:.1f} s")
        if path_png:
            plots.plot_run(recording, IMAGES / path_png)
        if signals_png:
            plots.plot_signals(recording, IMAGES / signals_png)
        if gif:
            animation.animate(recording, IMAGES / gif, speedup=speedup, fps=8)
    for picture in sorted(IMAGES.iterdir()):
        print(f"  {picture} ({picture.stat().st_size // 1024} KiB)")


if __name__ == "__main__":
    main()
