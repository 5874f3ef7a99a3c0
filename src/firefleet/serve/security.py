"""Who may ask the dashboard: the token, the Host and the websocket Origin (ASGI middleware).

- **Token.** When the server is bound beyond loopback every HTTP request and websocket
  must carry the token: ``?token=T`` in the URL (the link the server prints), the
  ``firefleet_token`` cookie the server sets when such a URL is opened, or an
  ``Authorization: Bearer T`` header. Compared in constant time.
- **Host.** Bound to loopback, a request must name a loopback host (``127.0.0.1``,
  ``localhost``, ``[::1]``): a page of another site that rebinds its DNS name to
  127.0.0.1 cannot read the dashboard.
- **Origin.** A websocket opened by a browser must come from the dashboard's own origin
  (``http(s)://`` + the Host it asked); a page of another site gets 403.

Refusals are plain ``403``/``401`` texts; nothing else is said about the server.
"""

from __future__ import annotations

import ipaddress
import secrets
from collections.abc import Awaitable, Callable, MutableMapping
from dataclasses import dataclass
from http.cookies import SimpleCookie
from typing import Any
from urllib.parse import parse_qs

__all__ = ["COOKIE", "Guard", "is_loopback", "new_token"]

COOKIE = "firefleet_token"

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
App = Callable[[Scope, Receive, Send], Awaitable[None]]

_LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")


def is_loopback(host: str) -> bool:
    """Whether binding ``host`` keeps the server on this machine.

    Examples
    --------
    >>> from firefleet.serve.security import is_loopback
    >>> is_loopback("127.0.0.1"), is_loopback("localhost"), is_loopback("0.0.0.0")
    (True, True, False)
    """
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def new_token() -> str:
    """A fresh random token (32 URL-safe characters)."""
    return secrets.token_urlsafe(24)


def _host_name(host_header: str) -> str:
    """``127.0.0.1:8000`` -> ``127.0.0.1``, ``[::1]:80`` -> ``::1``."""
    if host_header.startswith("["):
        return host_header[1:].split("]", 1)[0]
    return host_header.rsplit(":", 1)[0] if host_header.count(":") == 1 else host_header


@dataclass(frozen=True)
class Guard:
    """ASGI middleware in front of the dashboard.

    Attributes
    ----------
    app : ASGI app
    token : str or None
        Required on every request when not None.
    loopback_only : bool
        Refuse requests naming a host other than a loopback one (DNS rebinding).
    """

    app: App
    token: str | None
    loopback_only: bool

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}
        host = headers.get("host", "")
        if self.loopback_only and _host_name(host).lower() not in _LOOPBACK_NAMES:
            await _refuse(scope, receive, send, 403, "host not allowed")
            return
        if scope["type"] == "websocket":
            origin = headers.get("origin")
            if origin is not None and origin not in (f"http://{host}", f"https://{host}"):
                await _refuse(scope, receive, send, 403, "origin not allowed")
                return
        from_query = False
        if self.token is not None:
            query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
            given = query.get("token", [None])[0]
            from_query = given is not None
            if given is None:
                auth = headers.get("authorization", "")
                given = auth[7:] if auth.lower().startswith("bearer ") else None
            if given is None and "cookie" in headers:
                jar: SimpleCookie = SimpleCookie()
                try:
                    jar.load(headers["cookie"])
                except Exception:  # a malformed cookie header is no token
                    jar = SimpleCookie()
                given = jar[COOKIE].value if COOKIE in jar else None
            if given is None or not secrets.compare_digest(given.encode(), self.token.encode()):
                await _refuse(scope, receive, send, 401, "token required")
                return
        if not (from_query and scope["type"] == "http"):
            await self.app(scope, receive, send)
            return
        cookie = f"{COOKIE}={self.token}; Path=/; HttpOnly; SameSite=Strict".encode("latin-1")

        async def send_with_cookie(message: Message) -> None:
            if message["type"] == "http.response.start":
                message["headers"] = [*message.get("headers", []), (b"set-cookie", cookie)]
            await send(message)

        await self.app(scope, receive, send_with_cookie)


async def _refuse(scope: Scope, receive: Receive, send: Send, status: int, text: str) -> None:
    if scope["type"] == "websocket":
        await receive()  # websocket.connect
        await send({"type": "websocket.close", "code": 1008, "reason": text})  # HTTP 403
        return
    body = text.encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"text/plain; charset=utf-8"),
                (b"content-length", str(len(body)).encode()),
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})
