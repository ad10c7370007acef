"""Issue 46's hardening of the panel: the server answers only this machine's pages (Host checked,
a token), its kernels are bounded, the recordings grow linearly and are checked against a
limit before writing, every value typed or passed to the panel's computations is one line,
and a failed action leaves nothing of the one before it on the page."""

from __future__ import annotations

import html
import http.client
import json
import os
import re
import signal
import socket
import subprocess
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from nfarm.publishing import panel_compute as pc
from nfarm.publishing.panel_app import local_host
from nfarm.publishing.panel_server import new_token, panel_url, voila_command, voila_environment

TINY_NOTEBOOK = {
    "cells": [{"cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [],
               "source": ["print('the tiny panel')"]}],
    "metadata": {"kernelspec": {"display_name": "nfarm", "language": "python", "name": "nfarm"}},
    "nbformat": 4, "nbformat_minor": 5}


def one_line(text: str) -> str:
    """A page's message row as the reader sees it."""
    return html.unescape(re.sub(r"<[^>]+>", "", text))


# -- the server ----------------------------------------------------------------------------------


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """The panel's server (as ``make panel`` starts it) on a tiny notebook: a kernel starts in
    about a second, and what is checked is the server's, not the notebook's."""

    def __init__(self, directory: Path, **limits):
        self.port, self.token = free_port(), new_token()
        notebook = directory / "tiny.ipynb"
        notebook.write_text(json.dumps(TINY_NOTEBOOK))
        self.log = directory / "voila.log"
        with open(self.log, "w") as log:
            self.proc = subprocess.Popen(voila_command(self.port, notebook, connection_dir=directory, **limits),
                                         env=voila_environment(directory, self.token), stdout=log,
                                         stderr=subprocess.STDOUT, start_new_session=True)
        deadline = time.monotonic() + 120
        while self.request("/voila/static/voila.js", token=False)[0] != 200:
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.stop()
                pytest.fail(f"the panel's server did not start: {self.log.read_text()[-2000:]}")
            time.sleep(0.25)

    def request(self, path: str, *, token: bool = True, host: str | None = None, method: str = "GET",
                headers: dict | None = None) -> tuple[int, dict, str]:
        """``(status, headers, body)`` of one request, redirects not followed."""
        if token:
            path += ("&" if "?" in path else "?") + f"token={self.token}"
        connection = http.client.HTTPConnection("127.0.0.1", self.port, timeout=60)
        try:
            connection.putrequest(method, path, skip_host=True)
            connection.putheader("Host", host or f"127.0.0.1:{self.port}")
            for key, value in (headers or {}).items():
                connection.putheader(key, value)
            connection.endheaders()
            response = connection.getresponse()
            return response.status, dict(response.getheaders()), response.read().decode("utf-8", "replace")
        except OSError:
            return 0, {}, ""
        finally:
            connection.close()

    def page(self) -> tuple[int, str]:
        """Load the page with the token: its status and its kernel's id ("" when none)."""
        status, _, body = self.request("/")
        found = re.search(r'"kernelId":\s*"([0-9a-f-]+)"', body)
        return status, found.group(1) if found else body

    def stop(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)        # Voilà shuts its kernels down and exits
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """One page at a time, no culling (the kernel limit and the page's own shutdown are seen)."""
    running = Server(tmp_path_factory.mktemp("panel-server"), max_kernels=1, cull_idle_s=0)
    yield running
    running.stop()


WEBSOCKET = {"Connection": "Upgrade", "Upgrade": "websocket", "Sec-WebSocket-Version": "13",
             "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ=="}


def test_the_server_answers_only_its_own_machine_and_the_token(server):
    port = server.port
    # A DNS-rebinding page: its requests carry its own domain in Host, and are refused, page,
    # static files and kernels alike, token or not.
    for host in (f"evil.example:{port}", "evil.example", f"127.0.0.1.nip.io:{port}", f"localhost.evil:{port}"):
        for path in ("/", "/voila/static/voila.js", "/api/kernels/0"):
            status = server.request(path, host=host)[0]
            assert status in (400, 403), (host, path, status)
    # Without the token (or with another): no page (the login form instead), no kernel, no
    # websocket, no shutdown.
    for path in ("/", f"/?token={new_token()}"):
        status, headers, body = server.request(path, token=False)
        assert status in (302, 403) and "the tiny panel" not in body
        if status == 302:
            assert headers["Location"].startswith("/login")
    status, kernel = server.page()
    assert status == 200 and re.fullmatch(r"[0-9a-f-]{36}", kernel), kernel
    assert server.request(f"/api/kernels/{kernel}", token=False)[0] == 403
    assert server.request(f"/api/kernels/{kernel}/channels", token=False, headers=WEBSOCKET)[0] == 403
    assert server.request(f"/voila/api/shutdown/{kernel}", token=False, method="POST")[0] == 403
    # With the token, on any localhost name, it is served.
    status, _, body = server.request(f"/api/kernels/{kernel}", host=f"localhost:{port}")
    assert status == 200 and json.loads(body)["id"] == kernel
    # The page's kernel ends when the page closes (the page posts this), freeing its place.
    assert server.request(f"/voila/api/shutdown/{kernel}", method="POST")[0] == 204
    assert server.request(f"/api/kernels/{kernel}")[0] == 404


def test_a_page_beyond_the_kernel_limit_is_refused_in_one_line(server):
    status, first = server.page()
    assert status == 200
    try:
        status, _, body = server.request("/")
        assert status == 503
        text = one_line(body)
        assert "its limit of 1" in text and "close a page" in text
    finally:
        assert server.request(f"/voila/api/shutdown/{first}", method="POST")[0] == 204
    assert server.page()[0] == 200


def test_an_idle_kernel_without_a_page_is_culled(tmp_path):
    culling = Server(tmp_path, max_kernels=2, cull_idle_s=2, cull_interval_s=1)
    try:
        status, kernel = culling.page()           # loaded, never connected: a page that went away
        assert status == 200
        deadline = time.monotonic() + 60
        while culling.request(f"/api/kernels/{kernel}")[0] == 200 and time.monotonic() < deadline:
            time.sleep(0.5)
        assert culling.request(f"/api/kernels/{kernel}")[0] == 404
    finally:
        culling.stop()
    assert "Culling" in culling.log.read_text()


@pytest.mark.parametrize("host, ok", [("127.0.0.1", True), ("127.0.0.1:8866", True), ("127.5.6.7:1", True),
                                      ("localhost:8866", True), ("LOCALHOST", True), ("[::1]:8866", True),
                                      ("evil.example:8866", False), ("127.0.0.1.evil.example", False),
                                      ("0.0.0.0:8866", False), ("[::]:8866", False), ("", False),
                                      ("192.168.1.2:8866", False), ("localhost.:8866", False)])
def test_only_loopback_names_are_local(host, ok):
    assert local_host(host) is ok


def test_the_printed_address_holds_a_fresh_token():
    a, b = new_token(), new_token()
    assert a != b and len(a) >= 43 and re.fullmatch(r"[A-Za-z0-9_-]+", a)
    assert panel_url(8866, a) == f"http://127.0.0.1:8866/?token={a}"
    command = voila_command(8866)
    assert not any("allow_remote_access" in part or "token" in part.lower() for part in command)
    with pytest.raises(ValueError, match="max_kernels"):
        voila_command(8866, max_kernels=0)
    with pytest.raises(ValueError, match="token"):
        voila_environment(Path("/tmp"), "")


# -- the command line ----------------------------------------------------------------------------


def test_panel_start_up_errors_are_one_line_before_any_address(tmp_path, monkeypatch, capsys):
    from nfarm import __main__ as cli
    from nfarm.publishing import panel_server

    def not_here(*args):
        raise AssertionError("the panel went on to start Voilà in the test process")

    monkeypatch.setattr(os, "execve", not_here)
    (tmp_path / "panel").write_text("a file where the server's directory goes")
    monkeypatch.setattr(panel_server, "BUILD", tmp_path)
    assert cli.panel_command(free_port()) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1
    assert "panel/jupyter" in err and "is a file, not a directory" in err
