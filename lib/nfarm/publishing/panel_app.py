"""The panel's Voilà server, held to the local machine: ``python -m nfarm.publishing.panel_app
NOTEBOOK [Voilà options]`` (:func:`nfarm.publishing.panel_server.voila_command` writes the
command; ``make panel`` runs it).

Voilà as shipped (0.5) serves any ``Host`` (it sets tornado's ``allow_remote_access``) and, by
default, no token: a web page on a domain that resolves to 127.0.0.1 (DNS rebinding) could load
the panel and drive it. :class:`PanelVoila` answers only the local machine's own names:

* every request's ``Host`` must be a loopback address or ``localhost`` (with any port), the
  static files' too (:func:`local_host`); another name gets 403;
* pages, kernels and their websockets need the token (``?token=…`` in the URL that
  ``make panel`` prints, as Jupyter's; the browser keeps it as a login cookie). The token is
  read from the environment variable :data:`TOKEN_ENV` (not from the command line, which other
  users of the machine can read), and removed from the environment before any kernel starts;
  the server refuses to start without one;
* no file is served from the notebook's directory (``/voila/files/`` allows nothing);
* :class:`PanelKernelManager` refuses a page's kernel beyond ``max_kernels`` live ones (503,
  one line), and culls kernels left idle (``MappingKernelManager.cull_idle_timeout``); a
  page's kernel is shut down when the page closes (Voilà's page sends that request).
"""

from __future__ import annotations

import ipaddress
import os
import re
import sys
from datetime import timedelta

from jupyter_server._tz import utcnow
from jupyter_server.services.kernels.kernelmanager import AsyncMappingKernelManager
from tornado import web
from traitlets import Integer
from voila.app import Voila

from .panel_server import TOKEN_ENV

__all__ = ["TOKEN_ENV", "LOCAL_HOSTNAMES", "local_host", "PanelKernelManager", "PanelVoila", "main"]

#: Names, besides loopback addresses, under which the panel answers.
LOCAL_HOSTNAMES = ("localhost",)


def local_host(host: str | None) -> bool:
    """Whether a request's ``Host`` header names this machine's loopback interface:
    ``127.0.0.1`` (any ``127.x``), ``[::1]`` or ``localhost``, with or without a port.

    Example:
        >>> [local_host(h) for h in ("127.0.0.1:8866", "localhost", "[::1]:8866", "evil.example:8866", None)]
        [True, True, True, False, False]
    """
    if not host or not isinstance(host, str):
        return False
    # A Host is a name and an optional port in plain ASCII: no percent-encoding (an IPv6 zone
    # such as ``[::1%2Ftmp]`` would still parse as a loopback address), no white space, no path.
    match = re.fullmatch(r"(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9.-]+)(?::([0-9]{1,5}))?", host)
    if match is None or (match.group(2) is not None and not 0 < int(match.group(2)) <= 65535):
        return False
    name = match.group(1)
    if name.startswith("[") and name.endswith("]"):
        name = name[1:-1]
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return name.lower() in LOCAL_HOSTNAMES


class PanelKernelManager(AsyncMappingKernelManager):
    """Voilà's kernel manager with a limit on live kernels: a page asking for one more than
    :attr:`max_kernels` gets HTTP 503 and one line instead of a kernel (each is about 200 MB).
    Idle kernels are culled as Jupyter's (``cull_idle_timeout``), but not one still starting
    (for :attr:`start_grace` seconds): the page being built waits for it."""

    max_kernels = Integer(4, config=True, help="Kernels (open pages) alive at once; more are refused.")
    start_grace = Integer(120, config=True, help="Seconds a kernel that has not yet answered is not "
                                                 "culled (a slow start is no idleness).")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._starting = 0

    async def start_kernel(self, *, kernel_id=None, path=None, **kwargs):
        if kernel_id is not None and kernel_id in self:
            return await super().start_kernel(kernel_id=kernel_id, path=path, **kwargs)
        live = len(self.list_kernel_ids()) + self._starting
        if live >= self.max_kernels:
            message = (f"the panel runs {live} kernels, its limit of {self.max_kernels} (one per open "
                       f"page): close a page of the panel, or wait for an idle page's kernel to be shut "
                       f"down, and reload")
            raise web.HTTPError(503, message, reason=message)
        self._starting += 1
        try:
            return await super().start_kernel(kernel_id=kernel_id, path=path, **kwargs)
        finally:
            self._starting -= 1


    async def cull_kernel_if_idle(self, kernel_id):
        kernel = self._kernels.get(kernel_id)
        if kernel is not None and getattr(kernel, "execution_state", "") == "starting" and \
                utcnow() - kernel.last_activity < timedelta(seconds=self.start_grace):
            return None
        return await super().cull_kernel_if_idle(kernel_id)


def _host_checked(handler: type[web.RequestHandler]) -> type[web.RequestHandler]:
    """``handler`` refusing (403) a request whose ``Host`` is not this machine's own name."""
    class HostChecked(handler):
        def prepare(self):
            if not local_host(self.request.host):
                raise web.HTTPError(403, "the panel answers only to localhost names")
            return super().prepare()

    HostChecked.__name__ = HostChecked.__qualname__ = f"HostChecked{handler.__name__}"
    return HostChecked


class PanelVoila(Voila):
    """Voilà answering only this machine's pages, with a token (the module's docstring)."""

    def initialize(self, argv=None):
        super().initialize(argv)
        token = os.environ.pop(TOKEN_ENV, "")
        if not token:
            print(f"panel: no token given in {TOKEN_ENV}: the panel does not start without one "
                  f"(start it with `make panel`)", file=sys.stderr)
            self.exit(2)
        self.token = token
        self.voila_configuration.file_allowlist = []

    def init_settings(self):
        settings = super().init_settings()
        settings["allow_remote_access"] = False           # Voilà sets True: Host is checked
        settings["local_hostnames"] = list(LOCAL_HOSTNAMES)
        return settings

    def init_handlers(self):
        from jupyter_server.base.handlers import JupyterHandler

        handlers = []
        for pattern, handler, *rest in super().init_handlers():
            # Jupyter's handlers check Host themselves (with the settings above); tornado's
            # static-file handlers do not.
            if not issubclass(handler, JupyterHandler):
                handler = _host_checked(handler)
            handlers.append((pattern, handler, *rest))
        return handlers


def main(argv: list[str] | None = None) -> None:
    """Run the panel's Voilà server with ``argv`` (default: the command line's arguments)."""
    PanelVoila.launch_instance(argv)


if __name__ == "__main__":
    main()
