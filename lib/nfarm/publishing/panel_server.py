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

The server answers only this machine's own pages (:mod:`nfarm.publishing.panel_app`): a
``Host`` of a localhost name, a random token (:func:`new_token`) in the URL that ``make panel``
prints, required for pages, kernels and websockets; at most ``max_kernels`` kernels at once,
each shut down when its page closes or after ``cull_idle_s`` idle seconds without a page.
"""

from __future__ import annotations

import os
import secrets
import socket
import sys
from pathlib import Path

from ..infra.arguments import check_integer
from ..infra.paths import BUILD, NOTEBOOKS, ROOT, shown_path

__all__ = ["PANEL_NOTEBOOK", "DEFAULT_PORT", "new_token", "panel_url", "voila_command", "voila_environment",
           "check_port", "prepare", "serve"]

PANEL_NOTEBOOK = NOTEBOOKS / "arm_panel.ipynb"
DEFAULT_PORT = 8866
#: The project's Jupyter data directory (its Voilà template), put first on ``JUPYTER_PATH``.
JUPYTER_DIR = ROOT / "jupyter"
TEMPLATE = "nfarm-offline"
_NOT_LOADED = "@jupyter-notebook/lab-extension"
#: The environment variable that hands the server its token (as :data:`nfarm.publishing.panel_app.TOKEN_ENV`).
TOKEN_ENV = "NFARM_PANEL_TOKEN"


def _plain(value) -> str:
    """A value in a message: a number as it reads (``8866``, not ``np.int64(8866)``), text quoted."""
    if isinstance(value, (int, float)) or type(value).__module__ == "numpy" and hasattr(value, "item"):
        return str(value.item() if hasattr(value, "item") else value)
    return repr(str(value)) if isinstance(value, str) else type(value).__name__


def new_token() -> str:
    """A random token for the panel's URL (``secrets.token_urlsafe``: 256 bits, URL-safe)."""
    return secrets.token_urlsafe(32)


def panel_url(port: int, token: str) -> str:
    """The address ``make panel`` prints: ``http://127.0.0.1:<port>/?token=<token>``."""
    return f"http://127.0.0.1:{port}/?token={token}"


def voila_command(port: int, notebook: Path = PANEL_NOTEBOOK, *, connection_dir: Path | None = None,
                  max_kernels: int = 4, cull_idle_s: int = 600, cull_interval_s: int = 60) -> list[str]:
    """The command that serves ``notebook`` on ``http://127.0.0.1:<port>/`` (loopback only, no
    browser opened, no other port tried when that one is taken), answering localhost names
    only and with the token of :func:`voila_environment`
    (:class:`~nfarm.publishing.panel_app.PanelVoila`).

    At most ``max_kernels`` kernels (open pages) at once; a kernel idle for ``cull_idle_s``
    seconds with no page connected is shut down (checked every ``cull_interval_s`` seconds;
    ``cull_idle_s=0``: never). A page's kernel also ends when the page closes."""
    for name, value, low in (("max_kernels", max_kernels, 1), ("cull_idle_s", cull_idle_s, 0),
                             ("cull_interval_s", cull_interval_s, 1)):
        check_integer(name, value, low, numpy=False,
                      message=f"{name}: a whole number >= {low} needed, got {_plain(value)}")
    command = [sys.executable, "-m", "nfarm.publishing.panel_app", str(notebook), "--no-browser",
               f"--port={port}", "--Voila.port_retries=0", "--Voila.ip=127.0.0.1", f"--template={TEMPLATE}",
               f"--VoilaConfiguration.extension_denylist={_NOT_LOADED}",
               "--VoilaConfiguration.multi_kernel_manager_class=nfarm.publishing.panel_app.PanelKernelManager",
               f"--PanelKernelManager.max_kernels={max_kernels}",
               f"--MappingKernelManager.cull_idle_timeout={cull_idle_s}",
               f"--MappingKernelManager.cull_interval={cull_interval_s}",
               "--MappingKernelManager.cull_connected=False"]
    if connection_dir is not None:
        command.append(f"--Voila.connection_dir_root={connection_dir}")
    return command


def voila_environment(state_dir: Path, token: str) -> dict[str, str]:
    """The environment of the server: the project's template and the venv's kernel on
    ``JUPYTER_PATH``; Jupyter's runtime and data files (connection files, a secret) in
    ``state_dir``, not in the user's home; the token in
    :data:`~nfarm.publishing.panel_app.TOKEN_ENV` (the server takes it out before starting
    kernels)."""
    if not isinstance(token, str) or len(token) < 16:
        raise ValueError("token: a random text of at least 16 characters needed (new_token())")
    env = dict(os.environ)
    venv_share = Path(sys.prefix) / "share" / "jupyter"
    env["JUPYTER_PATH"] = os.pathsep.join([str(JUPYTER_DIR), str(venv_share)])
    env["JUPYTER_DATA_DIR"] = str(state_dir / "data")
    env["JUPYTER_RUNTIME_DIR"] = str(state_dir / "runtime")
    env.pop("JUPYTER_TOKEN", None)
    env[TOKEN_ENV] = token
    return env


def check_port(port: int) -> None:
    """Raise ``ValueError`` (one line) unless ``port`` is a port number free on 127.0.0.1."""
    check_integer("PORT", port, 1, 65535, numpy=False,
                  message=f"PORT must be a whole number from 1 to 65535, got {_plain(port)}")
    with socket.socket() as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError as error:
            raise ValueError(f"port {port} on 127.0.0.1 is not free ({error.strerror}): "
                             f"choose another, e.g. make panel PORT={port + 1}") from None


def prepare(port: int, state: Path | None = None) -> Path:
    """Everything the server needs before it starts, checked and made: the port free
    (:func:`check_port`), the notebook there, the state directory (default
    ``build/panel/jupyter/``) and its ``connections/`` made; returns the state directory.

    Raises:
        ValueError: one line naming what cannot be used and why.
    """
    check_port(port)
    if not PANEL_NOTEBOOK.is_file():
        raise ValueError(f"{shown_path(PANEL_NOTEBOOK)}: the panel's notebook is missing")
    state = state or BUILD / "panel" / "jupyter"
    try:
        (state / "connections").mkdir(parents=True, exist_ok=True)
        for sub in ("data", "runtime"):
            if (state / sub).exists() and not (state / sub).is_dir():
                raise NotADirectoryError(0, "not a directory", str(state / sub))
    except OSError as error:
        where = Path(error.filename) if error.filename else state
        blocking = next((p for p in (where, *where.parents) if p.exists() and not p.is_dir()), None)
        reason = f"{shown_path(blocking)} is a file, not a directory" if blocking else \
            (error.strerror or type(error).__name__)
        raise ValueError(f"cannot make the server's directory {shown_path(state)}: {reason}") from None
    if not os.access(state, os.W_OK | os.X_OK):
        raise ValueError(f"cannot write in the server's directory {shown_path(state)} (no permission)")
    return state


def serve(port: int = DEFAULT_PORT, token: str | None = None, **limits) -> None:
    """Become the Voilà server of the panel on ``port`` with ``token`` (default: a new one;
    the process is replaced, so Ctrl-C and the exit status are Voilà's own; ``python -m nfarm
    panel`` prepares, says the address with the token, then serves). ``limits`` go to
    :func:`voila_command` (``max_kernels``, ``cull_idle_s``, ``cull_interval_s``).

    Raises:
        ValueError: one line: the port cannot be used, or the server's directory cannot be
            made (:func:`prepare`).
    """
    state = prepare(port)
    command = voila_command(port, connection_dir=state / "connections", **limits)
    os.execve(command[0], command, voila_environment(state, token or new_token()))
