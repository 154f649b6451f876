"""A local HTTP server that serves a folder well or badly, for the OME-Zarr-over-HTTP fuzz cases
and tests: what a real server does wrong (an error status, a redirect loop, an answer cut short)
without a network.

A request for ``/<MODE>/<path>`` serves ``<root>/<path>`` as MODE says:

- ``ok``: the file (404 when there is none);
- ``500``, ``403``: that status for everything;
- ``loop``: a redirect to the same address, for ever;
- ``short``: the file with a Content-Length larger than what is sent before the connection closes;
- ``chunks-500``, ``chunks-short``: metadata files served well, chunks (every other file) as
  ``500`` or ``short``: the image opens, its bricks fail.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import unquote, urlsplit

MODES = ("ok", "500", "403", "loop", "short", "chunks-500", "chunks-short")
#: Zarr's metadata files (v2 and v3): served well in the ``chunks-*`` modes.
METADATA = frozenset({".zgroup", ".zattrs", ".zarray", ".zmetadata", "zarr.json"})
#: Bytes a ``short`` answer promises beyond what it sends.
MISSING_BYTES = 100


class _Handler(BaseHTTPRequestHandler):
    server: _Server

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        self._answer(body=True)

    def do_HEAD(self) -> None:  # noqa: N802
        self._answer(body=False)

    def log_message(self, format: str, *args: object) -> None:  # noqa: A002 - http.server's signature
        """Quiet: a fuzz run's output is its report."""

    def _answer(self, body: bool) -> None:
        mode, _, rel = unquote(urlsplit(self.path).path).lstrip("/").partition("/")
        file = (self.server.root / rel).resolve()
        if mode not in MODES or not file.is_relative_to(self.server.root):
            return self._status(404, body)
        if mode.startswith("chunks-"):
            mode = "ok" if file.name in METADATA else mode.removeprefix("chunks-")
        if mode in ("500", "403"):
            return self._status(int(mode), body)
        if mode == "loop":
            self.send_response(302)
            self.send_header("Location", self.path)
            self.send_header("Content-Length", "0")
            self.end_headers()
            return None
        if not file.is_file():
            return self._status(404, body)
        data = file.read_bytes()
        self.send_response(200)
        self.send_header("Content-Length", str(len(data) + (MISSING_BYTES if mode == "short" else 0)))
        self.end_headers()
        if body:
            self.wfile.write(data)
        self.close_connection = mode == "short"
        return None

    def _status(self, code: int, body: bool) -> None:
        text = f"{code}\n".encode()
        self.send_response(code)
        self.send_header("Content-Length", str(len(text)))
        self.end_headers()
        if body:
            self.wfile.write(text)


class _Server(ThreadingHTTPServer):
    daemon_threads = True

    def __init__(self, root: Path) -> None:
        super().__init__(("127.0.0.1", 0), _Handler)
        self.root = root.resolve()

    def handle_error(self, request: object, client_address: object) -> None:
        """Quiet about clients that hang up first (a reader that gave up on a bad answer); any
        other failure is the server's own, and printed."""
        if not isinstance(sys.exc_info()[1], ConnectionError):
            super().handle_error(request, client_address)


@contextmanager
def serving(root: str | Path) -> Iterator[str]:
    """Serve `root` on 127.0.0.1 in a thread while the block runs; yields the base address
    (``http://127.0.0.1:PORT``), to which ``/<MODE>/<path>`` is added."""
    server = _Server(Path(root))
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.1}, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(5)
