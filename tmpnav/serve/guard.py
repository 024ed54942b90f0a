"""What every request passes first: the token (with ``--token``) and the body's size limit.

A plain ASGI middleware, so that it also guards the event streams, and refuses a body larger
than the limit (413) as soon as its declared length, or the bytes read so far, pass it.
"""

from __future__ import annotations

import hmac
import json
from typing import Any
from urllib.parse import parse_qs

from tmpnav.serve.problems import MEDIA_TYPE, problem

Scope = dict[str, Any]


class Guard:
    """Refuses requests without the token (401) and bodies over ``max_body`` bytes (413)."""

    def __init__(self, app: Any, token: str | None, max_body: int):
        self.app, self.token, self.max_body = app, token, max_body

    async def __call__(self, scope: Scope, receive: Any, send: Any) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        public = scope["method"] == "GET" and (scope["path"] == "/" or scope["path"].startswith("/view/"))
        if self.token is not None and not public and not self._authorised(scope):
            await _send(
                send,
                401,
                "a token is required: send the header 'Authorization: Bearer <token>' (the view: ?token=<token>)",
                {"www-authenticate": 'Bearer realm="tmpnav"'},
            )
            return
        declared = dict(scope.get("headers") or []).get(b"content-length")
        if declared is not None and (not declared.isdigit() or int(declared) > self.max_body):
            await _send(send, 413, self._too_large())
            return
        if scope["method"] in ("GET", "HEAD", "DELETE", "OPTIONS"):  # no body: event streams pass through
            await self.app(scope, receive, send)
            return
        # the body is read here, up to the limit, and handed on whole: a chunked body that grows
        # past the limit is refused before any route sees it
        chunks, seen, more = [], 0, True
        while more:
            message = await receive()
            if message["type"] != "http.request":
                return  # the client went
            chunks.append(message.get("body", b""))
            seen += len(chunks[-1])
            more = message.get("more_body", False)
            if seen > self.max_body:
                await _send(send, 413, self._too_large())
                return
        body, given = b"".join(chunks), False

        async def replay() -> Any:
            nonlocal given
            if not given:
                given = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)

    def _too_large(self) -> str:
        return f"the request body is larger than the service's limit ({self.max_body} bytes)"

    def _authorised(self, scope: Scope) -> bool:
        assert self.token is not None
        given = dict(scope.get("headers") or []).get(b"authorization", b"").decode("latin-1")
        scheme, _, value = given.partition(" ")
        if scheme.lower() != "bearer":
            # EventSource and a page's address cannot carry a header: the query's token
            value = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [""])[0]
        return hmac.compare_digest(value.strip().encode(), self.token.encode())


async def _send(send: Any, status: int, message: str, headers: dict[str, str] | None = None) -> None:
    body = json.dumps(problem(status, [message], 2)).encode()
    raw = [(b"content-type", MEDIA_TYPE.encode()), (b"content-length", str(len(body)).encode())]
    raw += [(k.encode(), v.encode()) for k, v in (headers or {}).items()]
    await send({"type": "http.response.start", "status": status, "headers": raw})
    await send({"type": "http.response.body", "body": body})
