"""Bounds with a clear error naming the input (issue 43, items 7 and 8): a scheduler that
never answers, a port out of range, a manifest too large or with a huge cell, a campaign
count that is not a count, a run file with many columns. Each test fails on the code
before (the silent scheduler: connect had not returned after 60 s)."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from cylfric._parallel import connect


@pytest.fixture
def silent_server():
    """A TCP server that accepts connections and never says anything."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held, stop = [], threading.Event()

    def accept():
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                held.append(server.accept()[0])
            except OSError:
                continue

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    thread.join()
    for conn in held:
        conn.close()
    server.close()


def test_a_scheduler_that_never_answers_is_refused_in_bounded_time(silent_server):
    outcome = {}

    def attempt():
        try:
            connect(silent_server, timeout=2.0)
        except ValueError as exc:
            outcome["error"] = str(exc)

    started = time.monotonic()
    thread = threading.Thread(target=attempt, daemon=True)
    thread.start()
    thread.join(20)
    assert not thread.is_alive(), "connect did not return within 20 s"
    assert time.monotonic() - started < 10
    assert "no Dask scheduler answered within 2 s" in outcome["error"]
    assert silent_server in outcome["error"]


def test_a_port_out_of_range_is_named_at_once():
    started = time.monotonic()
    with pytest.raises(ValueError, match="port 99999 is not a TCP port"):
        connect("tcp://127.0.0.1:99999")
    assert time.monotonic() - started < 5
