"""``--viewer``: where a live session streams its recording while it runs (besides live.rrd).

* ``none``: only the file;
* ``spawn``: start a Rerun viewer (needs a display) and stream to it; it stays open after
  the session;
* ``serve`` or ``serve=PORT``: serve the stream over gRPC on PORT (default 9876): open it with
  ``rerun rerun+http://HOST:PORT/proxy``, a viewer that joins late gets what was logged
  before (up to the server's memory limit) as long as the session runs;
* ``connect=ADDR``: stream to a viewer (or ``rerun --serve-grpc``, ``rerun --save FILE``)
  already listening at ADDR, a ``rerun+http://HOST:PORT/proxy`` URL or a port on this
  machine; nothing listening there (within :data:`LISTEN_WAIT_S`) is an error, not a
  session that blocks once the stream's buffer is full.
"""

from __future__ import annotations

import socket
import subprocess
import time

import rerun as rr

from wipelab.errors import InputError

DEFAULT_PORT = 9876
VIEWER_CHOICES = "none, spawn, serve, serve=PORT or connect=ADDR"


def _port(text: str, option: str) -> int:
    if not text.isdigit() or not 0 < int(text) < 65536:
        raise InputError(f"--viewer: {option}={text}: not a port number (1-65535)")
    return int(text)


def _proxy_url(address: str) -> str:
    """``rerun+http://HOST:PORT/proxy`` of a connect address (a port means this machine)."""
    if address.isdigit():
        return f"rerun+http://127.0.0.1:{_port(address, 'connect')}/proxy"
    if not address.startswith(("rerun://", "rerun+http://", "rerun+https://")) \
            or not address.rstrip("/").endswith("/proxy"):
        raise InputError(f"--viewer: connect={address}: expected a port or a URL like "
                         "rerun+http://127.0.0.1:9876/proxy")
    return address


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


#: Seconds a viewer is waited for to listen (one just started takes a moment).
LISTEN_WAIT_S = 10.0


def _listening(host: str, port: int) -> bool:
    """Whether something accepts TCP connections at host:port within
    :data:`LISTEN_WAIT_S` seconds."""
    deadline = time.monotonic() + LISTEN_WAIT_S
    while True:
        try:
            with socket.create_connection((host, port), timeout=1.0):
                return True
        except OSError:
            if time.monotonic() >= deadline:
                return False
        time.sleep(0.1)


def _reachable(url: str) -> str:
    """``url`` (a checked proxy URL) if a viewer listens there; else InputError: the stream
    to an address nobody listens at fills the SDK's buffer and blocks the session."""
    from urllib.parse import urlsplit

    where = urlsplit(url.replace("rerun+", "", 1).replace("rerun://", "http://", 1))
    host, port = where.hostname or "127.0.0.1", where.port or DEFAULT_PORT
    if not _listening(host, port):
        raise InputError(f"--viewer: connect: nothing listens at {host}:{port} (start the "
                         f"viewer first, e.g. rerun --port {port}, or use --viewer serve)")
    return url


def _spawned_viewer() -> str:
    """Start a Rerun viewer listening on a free port (detached: it outlives the session);
    its proxy URL."""
    from wipelab.pipeline.recordings import has_display, rerun_program

    if not has_display():
        raise InputError("--viewer: spawn needs a display ($DISPLAY and $WAYLAND_DISPLAY are "
                         "unset); use --viewer serve and open the printed address elsewhere")
    port = _free_port()
    subprocess.Popen([rerun_program(), "--port", str(port)], start_new_session=True,
                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _listening("127.0.0.1", port)   # wait until it listens
    return f"rerun+http://127.0.0.1:{port}/proxy"


def parse_viewer(text: str) -> tuple[str, str | int | None]:
    """``--viewer`` -> (kind, argument), checked (InputError for anything else)."""
    kind, _, argument = text.partition("=")
    if kind in ("none", "spawn") and not argument:
        return kind, None
    if kind == "serve":
        return kind, _port(argument, "serve") if argument else DEFAULT_PORT
    if kind == "connect" and argument:
        return kind, _proxy_url(argument)
    raise InputError(f"--viewer: {text!r} is not one of {VIEWER_CHOICES}")


def viewer_sinks(text: str) -> tuple:
    """The Rerun sinks (besides the file) that ``--viewer`` asks for; a viewer spawned or a
    server started. Prints where to look (stderr) for ``serve``."""
    kind, argument = parse_viewer(text)
    if kind == "none":
        return ()
    if kind == "serve":
        try:
            sink = rr.GrpcServerSink(port=argument)
        except Exception as error:    # the port is taken, ...
            raise InputError(f"--viewer: serve={argument}: cannot serve there ({error})") \
                from None
        import click

        click.echo(f"live: streaming; open it with: rerun {sink.uri}", err=True)
        return (sink,)
    return (rr.GrpcSink(_spawned_viewer() if kind == "spawn" else _reachable(argument)),)
