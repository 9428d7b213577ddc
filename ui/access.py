"""Who may talk to the annotate server: this computer's browser, holding this session's token.

The page and its websocket read the user's frames and write their annotations, so
any request is refused (HTTP 403, before a websocket upgrade) unless

* its ``Host`` header names the loopback address the server listens on (this defeats
  DNS rebinding: a foreign name resolving to 127.0.0.1 still carries its own ``Host``);
* its ``Origin`` header, when the browser sends one, is that same address (a page on
  another site, or on another local port, cannot open the websocket);
* it carries the session's token: in the URL the command prints and opens
  (``?secret=TOKEN``, which trame's page also sends as the wslink handshake secret)
  or in the cookie set when that URL was first opened (for the page's own assets and
  its websocket, which the browser requests without the query).

The token is :func:`secrets.token_urlsafe` per run; trame's public default secret is
never used.
"""

from __future__ import annotations

import hmac
import secrets

#: The only interface the annotate server listens on.
LOOPBACK = "127.0.0.1"
#: Names of the loopback address a browser may use in ``Host`` and ``Origin``.
LOOPBACK_NAMES = ("127.0.0.1", "localhost")
#: URL query parameter carrying the token (trame's page reads it as the wslink secret).
TOKEN_PARAM = "secret"


def new_token() -> str:
    """A fresh random token for one run of the server (about 256 bits)."""
    return secrets.token_urlsafe(32)


def cookie_name(port: int) -> str:
    """Cookie holding the token; per port, since cookies are shared across a host's ports."""
    return f"vidcap-annotate-{port}"


def page_url(port: int, token: str) -> str:
    """The address the user opens: loopback, the port, the token."""
    return f"http://{LOOPBACK}:{port}/index.html?{TOKEN_PARAM}={token}"


def allowed_hosts(port: int) -> set[str]:
    """``Host`` header values that name this server."""
    return {f"{name}:{port}" for name in LOOPBACK_NAMES}


def _same(a: str | None, b: str) -> bool:
    return a is not None and hmac.compare_digest(a.encode(), b.encode())


def refusal(headers, query, cookies, port: int, token: str) -> str | None:
    """Why a request must be refused, or None when it may proceed.

    Parameters
    ----------
    headers : Mapping[str, str]
        The request's headers (case-insensitive mapping).
    query : Mapping[str, str]
        The URL's query parameters.
    cookies : Mapping[str, str]
        The request's cookies.
    port : int
        The port the server listens on.
    token : str
        This session's token.
    """
    hosts = allowed_hosts(port)
    if headers.get("Host", "").lower() not in hosts:
        return "foreign Host"
    origin = headers.get("Origin")
    if origin is not None and origin.lower() not in {f"http://{h}" for h in hosts}:
        return "foreign Origin"
    if not (_same(query.get(TOKEN_PARAM), token) or _same(cookies.get(cookie_name(port)), token)):
        return "no valid token"
    return None


def middleware(token: str):
    """An aiohttp middleware enforcing :func:`refusal` on every request (page, assets, ws).

    A request carrying the token in its URL gets the token as an HttpOnly, SameSite=Strict
    cookie, so the page's assets and websocket (requested without the query) pass too.
    """
    from aiohttp import web

    @web.middleware
    async def check_access(request, handler):
        port = request.transport.get_extra_info("sockname")[1] if request.transport else -1
        why = refusal(request.headers, request.query, request.cookies, port, token)
        if why is not None:
            return web.Response(status=403, text=f"vidcap annotate: refused ({why})\n")
        response = await handler(request)
        if _same(request.query.get(TOKEN_PARAM), token) and hasattr(response, "set_cookie"):
            response.set_cookie(cookie_name(port), token, httponly=True, samesite="Strict",
                                path="/")
        return response

    return check_access


def protect(server, token: str) -> None:
    """Make a trame ``server`` answer only requests :func:`refusal` lets through.

    When trame creates its aiohttp application (before it listens), add
    :func:`middleware` to it and make ``token`` the wslink handshake secret (in place of
    the ``--authKey`` default, wslink's public ``"wslink-secret"``).
    """

    @server.controller.on_server_bind.add
    def _bind(wslink_server):
        wslink_server.app.middlewares.append(middleware(token))
        server.protocol.updateSecret(token)
