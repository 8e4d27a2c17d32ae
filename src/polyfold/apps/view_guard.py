"""The viewer's gate: every HTTP request and websocket handshake that reaches `polyfold view` is
checked before viser sees it, so a page on another site (or a DNS-rebound name) gets 403 and not a
byte of the model.

A request passes when
- its Host header is one of the names the viewer answers to, with its port (127.0.0.1, localhost,
  [::1], or the --host address; listening on all interfaces (0.0.0.0, ::), any name, since the
  machine's own names are not known here),
- its Origin, when it has one, is that same http://host:port (a websocket handshake must have one:
  browsers always send it), and
- it carries the session token: `?token=...` in the URL the viewer prints (answered with a
  redirect to the same page without it, setting a cookie) or that cookie (HttpOnly,
  SameSite=Strict, named per port), which the page's own requests and its websocket send back.
Tokens are compared in constant time.

viser (1.1) has no hook for this: its server is websockets' `serve` called with viser's own
`process_request`. `guarded_start` wraps that one call while a ViserServer starts, so that
`Gate.check` runs first and viser's handler only for requests that pass; nothing of viser is
changed or copied.
"""

from __future__ import annotations

import contextlib
import hmac
import secrets
from collections.abc import Iterator
from dataclasses import dataclass, field
from http.cookies import CookieError, SimpleCookie
from urllib.parse import parse_qsl, urlencode, urlsplit, urlunsplit

TOKEN_PARAM = "token"
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "[::1]")
ANY_ADDRESS = ("0.0.0.0", "::")


def new_token() -> str:
    """A random session token (32 bytes, URL-safe)."""
    return secrets.token_urlsafe(32)


def cookie_name(port: int) -> str:
    """The token's cookie for the viewer on `port` (cookies are shared across ports of a host)."""
    return f"polyfold-view-{int(port)}"


@dataclass
class Gate:
    """What a request to the viewer must show (see the module docstring). host: the address
    listened on; token: the session's. `refused` counts the requests turned away."""

    host: str
    token: str = field(default_factory=new_token)
    refused: int = 0

    def names(self) -> tuple[str, ...] | None:
        """Host names the viewer answers to (None: any, when listening on all interfaces)."""
        if self.host in ANY_ADDRESS:
            return None
        own = f"[{self.host}]" if ":" in self.host else self.host
        return tuple(dict.fromkeys((*LOOPBACK_NAMES, own)))

    def url(self, port: int) -> str:
        """The page's URL with the token, on loopback when listening on all interfaces."""
        host = "127.0.0.1" if self.host in ANY_ADDRESS else self.host
        shown = f"[{host}]" if ":" in host else host
        return f"http://{shown}:{int(port)}/?{TOKEN_PARAM}={self.token}"

    def verdict(self, port: int, path: str, headers) -> tuple[int, dict[str, str]]:
        """(status, extra headers) for a request to `path` with `headers` (a mapping with .get),
        made to this viewer on `port`: 0 to pass it on to viser, 302 to set the token's cookie
        and drop the token from the URL, 403 to refuse."""
        host = headers.get("Host", "")
        names = self.names()
        if names is not None and host not in {f"{n}:{int(port)}" for n in names}:
            return 403, {}
        origin = headers.get("Origin")
        upgrade = (headers.get("Upgrade") or "").lower() == "websocket"
        if (origin is not None or upgrade) and origin != f"http://{host}":
            return 403, {}
        parts = urlsplit(path)
        query = parse_qsl(parts.query, keep_blank_values=True)
        given = [v for k, v in query if k == TOKEN_PARAM]
        if given and not upgrade:
            if not hmac.compare_digest(given[-1].encode(), self.token.encode()):
                return 403, {}
            rest = urlunsplit(("", "", parts.path or "/", urlencode([(k, v) for k, v in query if k != TOKEN_PARAM]), ""))
            return 302, {"Location": rest, "Cache-Control": "no-store",
                         "Set-Cookie": f"{cookie_name(port)}={self.token}; Path=/; HttpOnly; SameSite=Strict"}
        cookie = SimpleCookie()
        try:
            cookie.load(headers.get("Cookie") or "")
        except CookieError:
            return 403, {}
        morsel = cookie.get(cookie_name(port))
        if morsel is None or not hmac.compare_digest(morsel.value.encode(), self.token.encode()):
            return 403, {}
        return 0, {}

    def check(self, connection, request):
        """websockets' process_request: None to go on (to viser), else the Response to send."""
        from websockets.datastructures import Headers
        from websockets.http11 import Response

        status, extra = self.verdict(connection.local_address[1], request.path, request.headers)
        if status == 0:
            return None
        if status == 403:
            self.refused += 1
            body = b"403 Forbidden: open the URL polyfold view printed (with its token), on this machine\n"
            return Response(403, "Forbidden", Headers({"Content-Type": "text/plain; charset=utf-8",
                                                       "Content-Length": str(len(body)), "Connection": "close"}), body)
        return Response(302, "Found", Headers({**extra, "Content-Length": "0"}), b"")


@contextlib.contextmanager
def guarded_start(gate: Gate) -> Iterator[None]:
    """While a ViserServer is constructed (it returns once listening): its call of websockets'
    `serve` gets `gate.check` in front of viser's own process_request."""
    import websockets.asyncio.server as ws_server

    original = ws_server.serve

    def serve(handler, *args, process_request=None, **kwargs):
        async def checked(connection, request):
            refused = gate.check(connection, request)
            if refused is not None:
                return refused
            if process_request is None:
                return None
            answer = process_request(connection, request)
            if hasattr(answer, "__await__"):
                answer = await answer
            return answer

        return original(handler, *args, process_request=checked, **kwargs)

    ws_server.serve = serve
    try:
        yield
    finally:
        ws_server.serve = original
