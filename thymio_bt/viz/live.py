"""Watch a run in the browser as it goes: ``thymio-bt run MISSION --web [PORT]``.

A :class:`LiveServer` is an ``on_tick`` hook that serves, on 127.0.0.1 (``ssh -L`` and WSL reach
it; inside a container, 0.0.0.0 and a port published to the host's loopback), the run's page
(:mod:`thymio_bt.viz.page`) with no tick yet at ``/``, and the ticks recorded so far at
``/ticks?from=N`` (JSON: ``ticks`` from index N on, in the log's format, the run's ``events`` so
far, and its ``end`` once it has one). The page polls that every 200 ms and keeps every tick it
received, so it can be scrubbed during the run and after it. Python's own http.server, in a thread;
a request naming another host (DNS rebinding) is refused.

Example (a run served on a free port and asked for its ticks as the page asks):

>>> import json, urllib.request
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> server = LiveServer(0)
>>> result = Run(load_mission("square")).run(on_tick=server)  # with --realtime 1 from the CLI
>>> server.finish(result)
>>> with urllib.request.urlopen(f"{server.url}ticks?from=226") as answer:
...     data = json.load(answer)
>>> [tick["tick"] for tick in data["ticks"]], data["end"]["status"], len(data["events"])
([227, 228], 'SUCCESS', 16)
>>> with urllib.request.urlopen(server.url) as answer:
...     answer.headers["Content-Type"], b"connect-src 'self'" in answer.read()
('text/html; charset=utf-8', True)
>>> server.close()
"""

from __future__ import annotations

import json
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import TYPE_CHECKING, Any
from urllib.parse import parse_qs, urlsplit

from thymio_bt.errors import UserError
from thymio_bt.logs.entries import LogHeader, tree_nodes
from thymio_bt.logs.recording import Recorder, Recording, robot_shape
from thymio_bt.viz.page import page_html
from thymio_bt.viz.page_data import event_rows, page_data

if TYPE_CHECKING:
    from thymio_bt.run.runner import Run, RunResult

#: the port ``--web`` serves on when none is given
DEFAULT_PORT = 8765
#: the most ticks one answer carries (a page that connects late catches up in a few requests)
BATCH = 2000
#: how long, after the run, the server waits for a page that is watching to fetch the end (s)
LINGER = 5.0


class LiveServer:
    """Serves the run's page and its ticks as they come (see the module docstring)."""

    def __init__(self, port: int = DEFAULT_PORT, address: str = "127.0.0.1") -> None:
        """Serve on ``address`` (loopback unless told: ``0.0.0.0`` inside a container) and ``port``
        (0: a free one, then :attr:`port`)."""
        self._recorder = Recorder(statuses=True)
        self._lock = threading.Lock()
        self._page = b""
        self._events: list[dict[str, Any]] = []
        self._end: dict[str, Any] | None = None
        self._watched = False  # a page asked for ticks
        self._delivered = False  # a page received the end
        try:
            self.httpd = ThreadingHTTPServer((address, port), self._handler())
        except OSError as exc:
            raise UserError(
                f"--web: cannot serve on {address}:{port}: {exc.strerror or exc} (hint: another port, e.g. --web 8766)"
            ) from None
        self.port = self.httpd.server_address[1]
        self.url = f"http://127.0.0.1:{self.port}/"
        self._thread = threading.Thread(target=self.httpd.serve_forever, name="thymio-bt web", daemon=True)
        self._thread.start()

    def begin(self, run: Run) -> None:
        """Make the page of ``run`` before its first tick: its maze, its tree, no tick yet."""
        mission = run.mission
        header = LogHeader(
            mission=mission.name,
            seed=run.seed,
            tick_hz=mission.tick_hz,
            tree=tree_nodes(run.root),
            robot=robot_shape(run.backend.model),
        )
        start = Recording(maze=mission.maze, mission=mission.name, header=header)
        with self._lock:
            self._page = page_html([page_data(start)], live=True).encode()

    def __call__(self, run: Run) -> None:
        """Record the tick ``run`` just made (the first call makes the page)."""
        if not self._page:
            self.begin(run)
        with self._lock:
            self._recorder(run)
            self._events = event_rows(run.events)

    def finish(self, result: RunResult) -> None:
        """The run ended: its outcome goes to the page with the last ticks."""
        end = self._recorder.finish(result).end
        with self._lock:
            self._events = event_rows(result.events)
            self._end = {k: end.get(k) for k in ("status", "reason", "code", "failed_path", "sim_time", "collisions")}

    def close(self) -> None:
        """Stop serving; a page that was watching gets up to :data:`LINGER` s to fetch the end first."""
        deadline = time.monotonic() + LINGER  # realtime: waits for a browser, not for the run
        while self._watched and self._end is not None and not self._delivered and time.monotonic() < deadline:
            time.sleep(0.05)  # realtime
        self.httpd.shutdown()
        self.httpd.server_close()

    def _ticks(self, start: int) -> bytes:
        with self._lock:
            self._watched = True
            ticks = self._recorder.samples[start : start + BATCH]
            last = start + len(ticks) >= len(self._recorder.samples)
            end = self._end if last else None
            if end is not None:
                self._delivered = True
            return json.dumps({"ticks": ticks, "events": self._events, "end": end}, allow_nan=False).encode()

    def _handler(self) -> type[BaseHTTPRequestHandler]:
        server = self

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:  # noqa: N802  # http.server's name
                host = (self.headers.get("Host") or "").rsplit(":", 1)[0]
                if host not in ("127.0.0.1", "localhost"):
                    self.send_error(403, "this server answers only to 127.0.0.1 and localhost")
                    return
                url = urlsplit(self.path)
                if url.path == "/":
                    with server._lock:
                        body, kind = server._page, "text/html; charset=utf-8"
                    if not body:
                        self.send_error(503, "the run has not started yet: reload in a moment")
                        return
                elif url.path == "/ticks":
                    try:
                        start = max(0, int(parse_qs(url.query).get("from", ["0"])[0]))
                    except ValueError:
                        self.send_error(400, "from must be a tick index")
                        return
                    body, kind = server._ticks(start), "application/json"
                else:
                    self.send_error(404)
                    return
                self.send_response(200)
                self.send_header("Content-Type", kind)
                self.send_header("Content-Length", str(len(body)))
                self.send_header("Cache-Control", "no-store")
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, format: str, *args: Any) -> None:  # noqa: A002  # http.server's name
                """Quiet: the run's summary is the output."""

        return Handler
