"""--viewer: what it accepts, and the one-line errors of what it does not."""

import pytest

from wipelab.errors import InputError
from wipelab.live.viewer import parse_viewer, viewer_sinks


@pytest.mark.parametrize("text, parsed", [
    ("none", ("none", None)), ("spawn", ("spawn", None)), ("serve", ("serve", 9876)),
    ("serve=9000", ("serve", 9000)),
    ("connect=9000", ("connect", "rerun+http://127.0.0.1:9000/proxy")),
    ("connect=rerun+http://10.0.0.2:9876/proxy", ("connect", "rerun+http://10.0.0.2:9876/proxy")),
])
def test_accepted_viewers(text, parsed):
    assert parse_viewer(text) == parsed


@pytest.mark.parametrize("text, says", [
    ("window", "not one of none, spawn, serve"), ("serve=http", "not a port number"),
    ("serve=70000", "not a port number"), ("connect=", "not one of"),
    ("connect=http://host:9876", "expected a port or a URL like"), ("none=1", "not one of"),
])
def test_refused_viewers(text, says):
    with pytest.raises(InputError, match="--viewer") as error:
        parse_viewer(text)
    assert says in str(error.value)


def test_spawn_without_a_display_says_what_to_do(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(InputError, match="spawn needs a display.*--viewer serve"):
        viewer_sinks("spawn")


def test_connect_streams_to_a_viewer_that_listens(monkeypatch):
    """A listening port is taken (the check waits for a viewer still starting), a closed
    one refused at once after the wait."""
    import socket

    import wipelab.live.viewer as viewer

    monkeypatch.setattr(viewer, "LISTEN_WAIT_S", 0.3)
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen()
        port = listener.getsockname()[1]
        (sink,) = viewer_sinks(f"connect={port}")
        assert sink is not None
    with pytest.raises(InputError, match=f"nothing listens at 127.0.0.1:{port}"):
        viewer_sinks(f"connect=rerun+http://127.0.0.1:{port}/proxy")
