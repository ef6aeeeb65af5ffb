"""Who may use the page: a token beyond this machine, as Jupyter does.

On loopback (127.0.0.1, ::1, localhost) the page is this machine's user's alone and needs no token. Served to
the network (``--host 0.0.0.0`` or any other address) it holds health data, so every request must carry a token:
a random one made at start (printed in the page's address, ``http://HOST:PORT/?token=...``) or one given with
``--token`` or ``WBSA_SERVE_TOKEN``. The browser that opens the printed address gets the token as a cookie
(HttpOnly, SameSite=Strict), so the page's own requests carry it; scripts send ``Authorization: token ...``.
A request without it is answered 403 before any route runs, so nothing is read, stored or computed.

The token protects who may ask; it does not encrypt. Beyond a trusted network put TLS in front (docs/serve.md).
"""

from __future__ import annotations

import hmac
import secrets
from urllib.parse import parse_qs

#: Addresses that only this machine reaches.
LOOPBACK = ("127.0.0.1", "localhost", "::1")
#: Name of the cookie and of the query parameter that carry the token.
TOKEN_NAME = "token"
_COOKIE = "wbsa_token"
#: Shortest token accepted from the user (characters).
MIN_TOKEN_CHARS = 16


def needs_token(host: str) -> bool:
    """Whether serving on ``host`` needs a token: any address other than loopback."""
    return host not in LOOPBACK


def choose_token(host: str, given: str | None) -> str | None:
    """The token the server will require on ``host``.

    Parameters
    ----------
    host : str
        The address it listens on.
    given : str or None
        A token given by the user (``--token`` or ``WBSA_SERVE_TOKEN``); ``""`` or None: none given.

    Returns
    -------
    str or None
        The given token; a new random one (``secrets.token_urlsafe(32)``, 43 characters) beyond loopback when
        none is given; None on loopback when none is given (no token required).

    Raises
    ------
    WbsaError
        A given token shorter than :data:`MIN_TOKEN_CHARS` characters or with characters outside ``A-Z a-z 0-9
        - _ .``.
    """
    from wbsa.errors import WbsaError

    if given:
        if len(given) < MIN_TOKEN_CHARS or not all(c.isascii() and (c.isalnum() or c in "-_.") for c in given):
            raise WbsaError(f"the token must be at least {MIN_TOKEN_CHARS} characters of A-Z, a-z, 0-9, '-', '_' or "
                            "'.'; leave --token out to have a random one made")
        return given
    return secrets.token_urlsafe(32) if needs_token(host) else None


def _cookie(headers: dict[bytes, bytes]) -> str | None:
    for part in headers.get(b"cookie", b"").decode("latin-1").split(";"):
        name, _, value = part.strip().partition("=")
        if name == _COOKIE:
            return value
    return None


class TokenGate:
    """ASGI middleware: a request without the token gets 403 and never reaches the application.

    Parameters
    ----------
    app : ASGI application
    token : str
        The token every request must carry (query ``?token=``, header ``Authorization: token ...`` or the cookie
        the page's first visit sets).
    """

    def __init__(self, app, token: str) -> None:
        self.app = app
        self.token = token

    def _carried(self, scope) -> tuple[bool, bool]:
        """(the request carries the token, it came in the query: set the cookie)."""
        headers = dict(scope.get("headers", []))
        query = parse_qs(scope.get("query_string", b"").decode("latin-1")).get(TOKEN_NAME, [])
        auth = headers.get(b"authorization", b"").decode("latin-1")
        offered = [*query, auth[6:].strip() if auth.lower().startswith("token ") else None, _cookie(headers)]
        ok = [o is not None and hmac.compare_digest(o.encode(), self.token.encode()) for o in offered]
        return any(ok), bool(query) and ok[0]

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] == "lifespan":
            return await self.app(scope, receive, send)
        allowed, from_query = self._carried(scope)
        if not allowed:
            if scope["type"] == "http":
                body = (b'{"error": "this page needs its token: open the address wbsa serve printed (it ends in '
                        b'?token=...), or send the header Authorization: token ..."}')
                await send({"type": "http.response.start", "status": 403,
                            "headers": [(b"content-type", b"application/json"),
                                        (b"content-length", str(len(body)).encode())]})
                await send({"type": "http.response.body", "body": body})
            elif scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 1008})
            return None
        if not from_query:
            return await self.app(scope, receive, send)
        cookie = f"{_COOKIE}={self.token}; Path=/; HttpOnly; SameSite=Strict".encode()

        async def send_with_cookie(message) -> None:
            if message["type"] == "http.response.start":
                message = {**message, "headers": list(message.get("headers", [])) + [(b"set-cookie", cookie)]}
            await send(message)

        await self.app(scope, receive, send_with_cookie)
