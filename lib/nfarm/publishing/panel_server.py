"""The arm panel as a local web page: ``make panel`` (``python -m nfarm panel``).

Voilà turns ``notebooks/arm_panel.ipynb`` into a web app: it runs the notebook in the project's
kernel and serves its widgets, with the notebook's code hidden. The page must work with the
network off, so everything it loads comes from the venv: the page template is Voilà's "lab"
template without its two Font Awesome stylesheets from a CDN (``jupyter/voila/templates/
nfarm-offline/``; the fonts themselves are bundled in Voilà's scripts), and the notebook
front-end's lab extension, built for a newer JupyterLab than Voilà's page and of no use there,
is not loaded (it logged a module-sharing error in the browser's console). The browser test
(``tests/test_panel_browser.py``) checks that every request the page makes goes to this
machine.
"""

from __future__ import annotations

import os
import socket
import sys
from pathlib import Path

from ..infra.paths import BUILD, NOTEBOOKS, ROOT

__all__ = ["PANEL_NOTEBOOK", "DEFAULT_PORT", "voila_command", "voila_environment", "check_port", "serve"]

PANEL_NOTEBOOK = NOTEBOOKS / "arm_panel.ipynb"
DEFAULT_PORT = 8866
#: The project's Jupyter data directory (its Voilà template), put first on ``JUPYTER_PATH``.
JUPYTER_DIR = ROOT / "jupyter"
TEMPLATE = "nfarm-offline"
_NOT_LOADED = "@jupyter-notebook/lab-extension"


def voila_command(port: int, notebook: Path = PANEL_NOTEBOOK, *, connection_dir: Path | None = None) -> list[str]:
    """The command that serves ``notebook`` on ``http://127.0.0.1:<port>/`` (loopback only, no
    browser opened, no other port tried when that one is taken)."""
    command = [sys.executable, "-m", "voila", str(notebook), "--no-browser", f"--port={port}",
               "--Voila.port_retries=0", "--Voila.ip=127.0.0.1", f"--template={TEMPLATE}",
               f"--VoilaConfiguration.extension_denylist={_NOT_LOADED}"]
    if connection_dir is not None:
        command.append(f"--Voila.connection_dir_root={connection_dir}")
    return command


def voila_environment(state_dir: Path) -> dict[str, str]:
    """The environment of the server: the project's template and the venv's kernel on
    ``JUPYTER_PATH``; Jupyter's runtime and data files (connection files, a secret) in
    ``state_dir``, not in the user's home."""
    env = dict(os.environ)
    venv_share = Path(sys.prefix) / "share" / "jupyter"
    env["JUPYTER_PATH"] = os.pathsep.join([str(JUPYTER_DIR), str(venv_share)])
    env["JUPYTER_DATA_DIR"] = str(state_dir / "data")
    env["JUPYTER_RUNTIME_DIR"] = str(state_dir / "runtime")
    return env


def check_port(port: int) -> None:
    """Raise ``ValueError`` (one line) unless ``port`` is a port number free on 127.0.0.1."""
    if isinstance(port, bool) or not isinstance(port, int) or not 1 <= port <= 65535:
        raise ValueError(f"PORT must be a whole number from 1 to 65535, got {port!r}")
    with socket.socket() as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError as error:
            raise ValueError(f"port {port} on 127.0.0.1 is not free ({error.strerror}): "
                             f"choose another, e.g. make panel PORT={port + 1}") from None


def serve(port: int = DEFAULT_PORT) -> None:
    """Become the Voilà server of the panel on ``port`` (the process is replaced, so Ctrl-C and
    the exit status are Voilà's own; ``python -m nfarm panel`` says the address first).

    Raises:
        ValueError: ``port`` is not a port number free on 127.0.0.1 (:func:`check_port`).
    """
    check_port(port)
    state = BUILD / "panel" / "jupyter"
    state.mkdir(parents=True, exist_ok=True)
    command = voila_command(port, connection_dir=state / "connections")
    (state / "connections").mkdir(exist_ok=True)
    os.execve(command[0], command, voila_environment(state))
