"""The animation of a run (``--gif``): a GIF, or an MP4 when ffmpeg is installed.

Drawn fast (``benchmarks/bench_pictures.py``: 7 to 8 times less CPU than a matplotlib animation
of the same frames, at 2.5 times the pixels): matplotlib draws the maze, the axes and the title once; each frame
puts that background back and draws only what moves, the robot and its rays. The trail's newest
piece is drawn into the background itself, so a long trail costs nothing per frame. Pillow writes
the time and the running behaviours, and maps every frame onto one palette made once, so the GIF
needs no colour quantization per frame.

Example:

>>> import tempfile
>>> from PIL import Image
>>> from thymio_bt.testing import recorded
>>> recording = recorded("square")
>>> with tempfile.TemporaryDirectory() as folder:
...     gif = Image.open(animate(recording, Path(folder) / "run.gif", speedup=8))
...     gif.size, gif.n_frames > 10
((960, 960), True)
"""

from __future__ import annotations

import itertools
import shutil
import subprocess
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from thymio_bt.errors import UserError
from thymio_bt.logs.entries import TickRecord
from thymio_bt.logs.recording import Recording
from thymio_bt.outputs import Output
from thymio_bt.robot.model import COURSE
from thymio_bt.viz.plots import draw_maze, outline, pyplot, rays

#: the animation's width in pixels; its height follows the maze's shape (between 400 and 960)
WIDTH = 960
#: the colours that move over the maze (trail, body, rays, text), blended into the palette
MOVING = ("tab:blue", "black", "tab:red", "0.7")
#: the band at the top, above the plot, where each frame's time and running behaviours are written
BAND = 34
#: how long the last frame stays (ms), so that the end can be seen before the GIF loops
HOLD = 2000


def ffmpeg_program(path: Path) -> str:
    """The ffmpeg program that writes ``path`` as an MP4; a :class:`UserError` when there is none
    (checked before the run: a long run must not end in this error)."""
    program = shutil.which("ffmpeg")
    if program is None:
        raise UserError(f"--gif {path}: cannot write .mp4: ffmpeg is not installed (hint: write a .gif instead)")
    return program


def animate(recording: Recording, path: str | Path, speedup: float = 4.0, fps: int = 10) -> Path:
    """A GIF (or MP4 when ffmpeg is installed) of the run at ``speedup`` times real time, written
    whole or not at all."""
    path = Path(path)
    mp4 = path.suffix.lower() == ".mp4"
    program = ffmpeg_program(path) if mp4 else ""
    samples = recording.samples
    if not samples:
        raise UserError("nothing to animate: the run has no ticks")
    step = max(1, round(speedup / fps * _rate(samples)))
    chosen = list(range(0, len(samples), step))
    if chosen[-1] != len(samples) - 1:
        chosen.append(len(samples) - 1)
    speed = f"x{speedup:g}"
    out = Output(path, "--gif", stdout_ok=False)
    with out.staged() as staged:
        canvas = _Canvas(recording, speed)
        try:
            frames = canvas.frames(chosen)
            if mp4:
                _write_mp4(frames, staged, fps, program, path)
            else:
                _write_gif(frames, staged, fps)
        finally:
            canvas.close()
    return path


class _Canvas:
    """The figure the frames are drawn on: the maze drawn once, the moving parts drawn per frame."""

    def __init__(self, recording: Recording, speed: str) -> None:
        from matplotlib.patches import Polygon
        from PIL import ImageFont

        self.plt = pyplot()
        self.recording = recording
        fig, ax = self.plt.subplots(figsize=(WIDTH / 100, WIDTH / 100), dpi=100)
        self.fig, self.ax = fig, ax
        draw_maze(ax, recording)
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        # the plot's width times the maze's shape, plus the title, the labels and the band; even, as
        # ffmpeg's yuv420p needs it
        height = min(max(round((WIDTH - 110) * (y1 - y0) / (x1 - x0)) + 110 + BAND, 400), WIDTH) // 2 * 2
        fig.set_size_inches(WIDTH / 100, height / 100)
        end = recording.end
        ax.set_title(
            f"{recording.mission}: {end.get('status', '')} after {end.get('sim_time', 0):.1f} s simulated "
            f"(played {speed})",
            fontsize=11,
        )
        fig.tight_layout(rect=(0, 0, 1, 1 - BAND / height))
        self.trail = ax.plot([], [], color="tab:blue", lw=1.6, solid_capstyle="butt", animated=True)[0]
        self.body = Polygon([(0, 0)] * len(COURSE.hull), closed=True, fc="tab:blue", ec="black", alpha=0.6)
        self.body.set_animated(True)
        ax.add_patch(self.body)
        self.rays = [ax.plot([], [], lw=1.0, animated=True)[0] for _ in COURSE.sensors]
        fig.canvas.draw()
        self.background = fig.canvas.copy_from_bbox(fig.bbox)
        from matplotlib import font_manager

        self.font = ImageFont.truetype(font_manager.findfont("DejaVu Sans"), 16)

    def close(self) -> None:
        """Free the figure."""
        self.plt.close(self.fig)

    def frames(self, chosen: list[int]) -> Iterator[Any]:
        """The RGB image (Pillow) of each chosen sample, in order."""
        import numpy as np
        from PIL import Image, ImageDraw

        samples, canvas, ax = self.recording.samples, self.fig.canvas, self.ax
        done = 0  # the samples whose trail is in the background
        for index in chosen:
            canvas.restore_region(self.background)
            if self._extend_trail(samples[max(done - 1, 0) : index + 1]):
                self.background = canvas.copy_from_bbox(self.fig.bbox)
            done = index + 1
            sample = samples[index]
            pose = sample["pose"]
            if pose is not None:
                self.body.set_xy(outline(pose))
                ax.draw_artist(self.body)
                for ray, (start, end, hit) in zip(self.rays, rays(pose, sample["prox"] or {}), strict=True):
                    ray.set_data([start[0], end[0]], [start[1], end[1]])
                    ray.set_color("tab:red" if hit else "0.7")
                    ax.draw_artist(ray)
            image = Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3])
            running = ", ".join(sample.get("running", [])) or "-"
            ImageDraw.Draw(image).text((12, 8), f"t = {sample['t']:5.1f} s   {running}", fill="black", font=self.font)
            yield image

    def _extend_trail(self, piece: list[TickRecord]) -> bool:
        """Draw the trail through ``piece`` (the samples since the last frame, the last one before
        them first) into the canvas, broken where the robot was deleted or moved; whether it drew."""
        drew = False
        for part in _parts(piece):
            if len(part) > 1:
                self.trail.set_data([p["x"] for p in part], [p["y"] for p in part])
                self.ax.draw_artist(self.trail)
                drew = True
        return drew


def _parts(samples: list[TickRecord]) -> Iterator[list[dict[str, float]]]:
    """The poses of ``samples`` in runs without a gap: a sample without a robot, or a jump of more
    than 5 cm between two ticks (a respawn), ends one."""
    part: list[dict[str, float]] = []
    for sample in samples:
        pose = sample["pose"]
        if pose is None or (part and abs(pose["x"] - part[-1]["x"]) + abs(pose["y"] - part[-1]["y"]) > 0.05):
            yield part
            part = []
        if pose is not None:
            part.append(pose)
    yield part


def _write_gif(frames: Iterable[Any], path: Path, fps: int) -> None:
    """The frames as a looping GIF, each mapped onto the palette of the first (no dithering: flat
    colours stay flat and the frames compress well)."""
    from PIL import Image

    images = iter(frames)
    first = next(images)
    palette = _palette(first)
    gif = [image.quantize(palette=palette, dither=Image.Dither.NONE) for image in itertools.chain([first], images)]
    durations = [round(1000 / fps)] * (len(gif) - 1) + [HOLD]
    gif[0].save(path, format="GIF", save_all=True, append_images=gif[1:], duration=durations, loop=0)


def _palette(first: Any) -> Any:
    """One palette for every frame: the colours of the first frame, and the moving parts' colours
    blended with the background in 16 steps (the antialiased edges of a trail drawn later)."""
    from matplotlib.colors import to_rgb
    from PIL import Image

    background = first.getpixel((0, 0))  # the figure's face: the band above the plot
    ramps = Image.new("RGB", (16, len(MOVING)))
    for row, colour in enumerate(MOVING):
        rgb = to_rgb(colour)
        for i in range(16):
            ramps.putpixel(
                (i, row), tuple(round(b + (255 * c - b) * i / 15) for c, b in zip(rgb, background, strict=True))
            )
    swatch = Image.new("RGB", (first.width, first.height + 40 * len(MOVING)))
    swatch.paste(first, (0, 0))
    swatch.paste(ramps.resize((first.width, 40 * len(MOVING)), Image.Resampling.NEAREST), (0, first.height))
    palette = swatch.quantize(colors=256, method=Image.Quantize.MEDIANCUT)
    # Pillow maps a colour onto a palette by boxes of 8 levels a channel, where it may pick a shade
    # near the background over the background itself (a white page came out light grey): the
    # entries within 8 levels of the background become the background
    colours = palette.getpalette() or []
    for i in range(0, len(colours), 3):
        if all(abs(c - b) < 8 for c, b in zip(colours[i : i + 3], background, strict=True)):
            colours[i : i + 3] = background
    palette.putpalette(colours)
    return palette


def _write_mp4(frames: Iterable[Any], path: Path, fps: int, program: str, target: Path) -> None:
    """The frames through ``program`` (ffmpeg) as an H.264 MP4 that players and browsers open, in
    ``path`` (the staged file of ``target``, which errors name)."""
    command = [program, "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24"]
    images = iter(frames)
    first = next(images)
    command += ["-s", f"{first.width}x{first.height}", "-r", str(fps), "-i", "-", "-pix_fmt", "yuv420p"]
    command += ["-vcodec", "libx264", "-f", "mp4", str(path)]
    process = subprocess.Popen(command, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
    assert process.stdin is not None
    try:
        for image in itertools.chain([first], images):
            process.stdin.write(image.tobytes())
        process.stdin.close()
    except BrokenPipeError:
        pass  # ffmpeg stopped: its error is read below
    error = process.stderr.read().decode(errors="replace").strip() if process.stderr else ""
    if process.wait() != 0:
        raise UserError(f"cannot write {target}: ffmpeg failed: {error[-300:] or 'no message'}")


def _rate(samples: list[TickRecord]) -> float:
    """Ticks per simulated second of the recording (10 when it cannot tell)."""
    if len(samples) < 2:
        return 10.0
    dt = samples[1]["t"] - samples[0]["t"]
    return 1.0 / dt if dt > 0 else 10.0


__all__ = ["WIDTH", "animate", "ffmpeg_program"]
