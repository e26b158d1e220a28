"""The console's web server: one page, its static files, the run's snapshots, a WebSocket.

Starlette (routing, static files, WebSockets) served by uvicorn: both are
small, well kept, and the usual pair for an ASGI app that needs no ORM or
forms.  The :class:`Hub` is the server's whole state: the run's port, the
console's :class:`~shary.console.view.View` of it, the scheme diagrams drawn
so far, and one outgoing queue per connected page.

Messages to the page are JSON: ``hello`` (title, mode), ``scheme`` (a
diagram), ``changes`` (see :mod:`shary.console.view`; ``reset: true`` empties
the page first), ``status`` and ``reply`` (to an operator message).  Events
that arrive together go out as one ``changes`` message.

Files: the page and its script come from the package; the only other files
served are the run's snapshots (``/run/snapshot-….png``), looked up by name in
the run's folder, never by a path.  No endpoint writes a file.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import sys
import threading
import time
from collections.abc import Iterator
from importlib import resources
from typing import Any
from urllib.parse import urlsplit

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import FileResponse, HTMLResponse, PlainTextResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from shary.console.diagrams import scheme_svg
from shary.console.operator import MAX_MESSAGE_BYTES, Refused, parse
from shary.console.ports import RunPort, run_file
from shary.console.view import Change, View
from shary.log.contextlog import LogEvent

QUEUE_LIMIT = 10_000
"""Messages waiting for one page; a page that falls this far behind is dropped
(it can reload), rather than letting the server's memory grow without end."""

LOOPBACK = ("127.0.0.1", "::1")
_encode = json.JSONEncoder(separators=(",", ":"), ensure_ascii=False).encode


class Hub:
    """The run, the view of it, and the pages watching (see the module's docstring)."""

    def __init__(self, port: RunPort, *, stamp: bool = False):
        self.port = port
        self.view = View(port.scheme)
        self.stamp = stamp
        """Add the server's wall clock (ms) to each message: the benchmark reads it."""
        self.clients: dict[WebSocket, asyncio.Queue[str]] = {}
        self.svgs: dict[str, str] = {}
        self._drawing: set[str] = set()
        self._pending: list[Change] = []
        self._flush_due = False
        self._status: dict[str, Any] = {}
        self._started = False

    # -- from the run ------------------------------------------------------------------

    def feed(self, event: LogEvent) -> None:
        """One event of the run: fold it, and send what changed with the next flush."""
        changes = self.view.apply(event)
        if not changes:
            return
        self._pending += changes
        for change in changes:
            self._draw_for(change)
        if not self._flush_due:
            self._flush_due = True
            asyncio.get_running_loop().call_soon(self._flush)

    def status(self, status: dict[str, Any]) -> None:
        self._status = status
        self.broadcast({"type": "status", "status": status})

    def _flush(self) -> None:
        self._flush_due = False
        if self._pending:
            changes, self._pending = self._pending, []
            self.broadcast({"type": "changes", "changes": changes})

    def broadcast(self, message: dict[str, Any]) -> None:
        if self.stamp:
            message["sent"] = time.time() * 1000
        text = _encode(message)
        for ws, out in list(self.clients.items()):
            if out.qsize() >= QUEUE_LIMIT:
                self.clients.pop(ws, None)
                out.put_nowait("")  # the page's sender stops
            else:
                out.put_nowait(text)

    def _draw_for(self, change: Change) -> None:
        """Draw the scheme a change shows: a task's, or a shared plan's task states."""
        if change[0] == "task":
            self._draw(change[4])
        elif change[0] == "plan":
            self._draw(change[3])

    def _draw(self, name: str) -> None:
        """Draw a scheme once, off the loop (``dot`` takes a while), then send it."""
        if name in self.svgs or name in self._drawing:
            return
        scheme = self.port.scheme(name)
        if scheme is None:
            return
        self._drawing.add(name)

        async def draw() -> None:
            try:
                self.svgs[name] = await asyncio.to_thread(scheme_svg, scheme)
            except (RuntimeError, OSError) as err:
                print(f"console: cannot draw scheme {name!r}: {err}", file=sys.stderr)
                return
            self.broadcast({"type": "scheme", "name": name, "svg": self.svgs[name]})

        asyncio.get_running_loop().create_task(draw())

    # -- the pages ------------------------------------------------------------------------

    async def connect(self, ws: WebSocket) -> None:
        origin = ws.headers.get("origin")
        if origin is not None and urlsplit(origin).netloc != ws.headers.get("host"):
            # a page from another site, in the operator's browser, must not steer the robot
            self.port.refused("unknown", "connect", f"a page from {origin[:100]!r}")
            await ws.close(code=1008)
            return
        await ws.accept()
        out: asyncio.Queue[str] = asyncio.Queue()
        hello = {"type": "hello", "title": self.port.title, "mode": self.port.mode}
        out.put_nowait(_encode(hello))
        for name, svg in self.svgs.items():
            out.put_nowait(_encode({"type": "scheme", "name": name, "svg": svg}))
        changes = (self.port.changes_at(self.port.end) if self.port.mode == "replay"
                   else self.view.snapshot())
        if self.port.mode == "replay":
            for change in changes:
                self._draw_for(change)
        out.put_nowait(_encode({"type": "changes", "reset": True, "changes": changes}))
        if self._status:
            out.put_nowait(_encode({"type": "status", "status": self._status}))
        self.clients[ws] = out
        if not self._started:
            self._started = True
            self.port.start(self.feed, self.status)
        sender = asyncio.get_running_loop().create_task(self._send(ws, out))
        try:
            while True:
                text = await ws.receive_text()
                self._operator(ws, text, out)
        except (WebSocketDisconnect, RuntimeError, KeyError):
            pass
        finally:
            self.clients.pop(ws, None)
            sender.cancel()

    async def _send(self, ws: WebSocket, out: asyncio.Queue[str]) -> None:
        with contextlib.suppress(WebSocketDisconnect, RuntimeError, OSError):
            while True:
                text = await out.get()
                if not text:
                    await ws.close()
                    return
                await ws.send_text(text)

    def _operator(self, ws: WebSocket, text: str, out: asyncio.Queue[str]) -> None:
        """One message from a page: checked, carried out or refused, logged, answered."""
        try:
            message = parse(text)
        except Refused as refused:
            self.port.refused(refused.by, "malformed", f"{refused.reason} in {refused.raw!r}")
            out.put_nowait(_encode({"type": "reply", "id": None, "ok": False,
                                    "error": refused.reason}))
            return
        if message["kind"] == "seek" and self.port.mode == "replay":
            changes = self.port.changes_at(float(message["time"]))
            out.put_nowait(_encode({"type": "changes", "reset": True, "changes": changes}))
            why = None
        else:
            why = self.port.handle(message, self.view)
            if why is not None:
                self.port.refused(message["by"], message["kind"], why)
        out.put_nowait(_encode({"type": "reply", "id": message.get("id"), "ok": why is None,
                                "error": why}))


def make_app(port: RunPort, *, stamp: bool = False, host: str = "127.0.0.1") -> Starlette:
    """The console's ASGI application for one run.

    Served on this machine only (the default), it answers only requests that name
    this machine (``Host``), so that a web page elsewhere cannot reach it through
    DNS rebinding; WebSockets from a page of another origin are refused too.
    """
    hub = Hub(port, stamp=stamp)
    static = resources.files("shary.console").joinpath("static")

    async def page(request: Request) -> Response:
        return HTMLResponse(static.joinpath("index.html").read_text("utf-8"))

    async def snapshot(request: Request) -> Response:
        name = request.path_params["name"]
        found = run_file(port.folder, name)
        if found is None:
            return PlainTextResponse("not found", status_code=404)
        return FileResponse(found, media_type="image/png")

    async def socket(ws: WebSocket) -> None:
        await hub.connect(ws)

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> Any:
        try:
            yield
        finally:
            await asyncio.to_thread(port.close)

    app = Starlette(routes=[
        Route("/", page),
        Route("/run/{name:path}", snapshot),
        WebSocketRoute("/ws", socket),
        Mount("/static", StaticFiles(directory=str(static)), name="static"),
    ], lifespan=lifespan, middleware=[Middleware(TrustedHostMiddleware, allowed_hosts=[
        *LOOPBACK, "localhost"])] if host in LOOPBACK else [])
    app.state.hub = hub
    return app


@contextlib.contextmanager
def serving(port: RunPort, *, host: str = "127.0.0.1", stamp: bool = False) -> Iterator[str]:
    """Serve the console in a background thread on a free port; yield its address.

    For tests, benchmarks and notebooks: the server stops (and the run with it)
    when the block ends.
    """
    import uvicorn

    config = uvicorn.Config(make_app(port, stamp=stamp, host=host), host=host, port=0,
                            log_level="warning", ws_max_size=MAX_MESSAGE_BYTES * 4,
                            timeout_graceful_shutdown=2, lifespan="on")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, name="shary-console", daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started:
        if not thread.is_alive() or time.monotonic() > deadline:
            raise RuntimeError("the console's server did not start")
        time.sleep(0.01)
    address = server.servers[0].sockets[0].getsockname()
    try:
        yield f"http://{host}:{address[1]}"
    finally:
        server.should_exit = True
        thread.join(timeout=15)


def serve(port: RunPort, host: str = "127.0.0.1", port_number: int = 8765, *,
          option: str = "--port") -> int:
    """Serve the console until interrupted (Ctrl-C); the address is printed first
    (``option``: the command's option that chooses the port, named when it is in use).

    The socket is bound here, before the server starts, so that an address in use
    is one clear line (exit status 2) and the address printed is one that listens.
    """
    import socket

    import uvicorn

    from shary.log.terminal import error

    try:
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        listening = socket.socket(family, socket.SOCK_STREAM)
        listening.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listening.bind((host, port_number))
    except OSError as err:
        return error(f"cannot listen on {host} port {port_number}: {err.strerror or err} "
                     f"(another server there? choose one with {option} N)")
    app = make_app(port, host=host)
    config = uvicorn.Config(app, log_level="warning", ws_max_size=MAX_MESSAGE_BYTES * 4,
                            timeout_graceful_shutdown=2, lifespan="on")
    server = uvicorn.Server(config)
    shown = f"[{host}]" if ":" in host else host
    print(f"shary console: http://{shown}:{port_number}/  ({port.title}; Ctrl-C to stop)",
          flush=True)
    server.run(sockets=[listening])
    return 0
