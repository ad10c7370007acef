"""The arm panel as ``make panel`` serves it, in headless Chromium: the page renders its widgets,
a joint slider moved with the keyboard changes the tool pose shown, and no request leaves the
machine. Skipped, with one line, where Chromium and its driver are not installed
(``apt-get install chromium chromium-driver``)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import time
import urllib.request
from urllib.parse import urlparse

import pytest

from nfarm.__main__ import panel_command
from nfarm.publishing.panel_server import check_port, new_token, panel_url, voila_command, voila_environment

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DRIVER = shutil.which("chromedriver")
LOCAL = {"127.0.0.1", "localhost", "::1", "[::1]"}
SLIDER = ".widget-slider .noUi-handle[role=slider]"      # ipywidgets 8 draws a slider with noUiSlider
CANVAS = ".jupyter-matplotlib canvas"
ERRORS = ['.jp-OutputArea-output[data-mime-type="application/vnd.jupyter.stderr"]',   # a cell that raised
          ".jupyter-widgets-error-widget", ".voila-error"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_taken_port_is_refused_in_one_line(capsys, monkeypatch):
    def not_here(*args):
        raise AssertionError("the panel went on to start Voilà in the test process")

    monkeypatch.setattr(os, "execve", not_here)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        assert panel_command(port) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"port {port}" in err and "PORT=" in err
    for bad in (0, 70000, "8866", True):
        with pytest.raises(ValueError, match="PORT must be a whole number"):
            check_port(bad)


@pytest.fixture
def server(tmp_path):
    port, token = free_port(), new_token()
    log = open(tmp_path / "voila.log", "w")
    proc = subprocess.Popen(voila_command(port, connection_dir=tmp_path), env=voila_environment(tmp_path, token),
                            stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    base = f"http://127.0.0.1:{port}/"
    try:
        deadline = time.monotonic() + 120
        while True:       # a static file, not the page: every request of the page starts a kernel
            if proc.poll() is not None:
                pytest.fail(f"voila exited with {proc.returncode}: {(tmp_path / 'voila.log').read_text()[-2000:]}")
            try:
                with urllib.request.urlopen(base + "voila/static/voila.js", timeout=2) as response:
                    if response.status == 200:
                        break
            except OSError:
                if time.monotonic() > deadline:
                    pytest.fail("voila did not answer within 120 s")
                time.sleep(0.25)
        yield panel_url(port, token)       # the page needs the token, as make panel prints it
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)       # Voilà shuts its kernels down and exits
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        log.close()


def requested(driver) -> list[str]:
    urls = []
    for entry in driver.get_log("performance"):
        message = json.loads(entry["message"])["message"]
        if message["method"] == "Network.requestWillBeSent":
            urls.append(message["params"]["request"]["url"])
        elif message["method"] == "Network.webSocketCreated":
            urls.append(message["params"]["url"])
    return urls


@pytest.mark.skipif(not (CHROMIUM and DRIVER),
                    reason="Chromium and its driver are not installed (apt-get install chromium chromium-driver)")
def test_a_slider_moved_with_the_keyboard_changes_the_pose_shown(server):
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support import expected_conditions as ec
    from selenium.webdriver.support.ui import WebDriverWait

    options = Options()
    options.binary_location = CHROMIUM
    for argument in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                     "--window-size=1400,1000", "--disable-background-networking", "--no-first-run",
                     # no name resolves but this machine's: a request that would leave it fails, and is logged
                     "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE localhost, EXCLUDE 127.0.0.1"):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"performance": "ALL", "browser": "ALL"})
    driver = webdriver.Chrome(service=Service(DRIVER), options=options)
    try:
        driver.get(server)
        wait = WebDriverWait(driver, 180)
        handle = wait.until(ec.element_to_be_clickable((By.CSS_SELECTOR, SLIDER)))
        wait.until(ec.visibility_of_element_located((By.CSS_SELECTOR, CANVAS)))

        def pose_text(d):
            shown = [e.text for e in d.find_elements(By.CSS_SELECTOR, ".widget-html-content") if "position [mm]" in e.text]
            return shown[0] if shown else None

        before = wait.until(pose_text)
        start = handle.get_attribute("aria-valuenow")
        for _ in range(4):
            handle.send_keys(Keys.ARROW_RIGHT)           # focuses the handle, then moves it one step
        wait.until(lambda d: pose_text(d) not in (None, before))
        assert float(handle.get_attribute("aria-valuenow")) > float(start)
        body = driver.find_element(By.TAG_NAME, "body").text
        errors = [e.text[:200] for selector in ERRORS for e in driver.find_elements(By.CSS_SELECTOR, selector)]
        assert not errors and "Error displaying widget" not in body, errors
        assert "Forward kinematics" in body and "Inverse kinematics" in body
        severe = [e["message"][:300] for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not severe, severe
        outside = [u for u in requested(driver)
                   if urlparse(u).scheme not in ("data", "blob", "about") and urlparse(u).hostname not in LOCAL]
        assert not outside, outside
    finally:
        driver.quit()
