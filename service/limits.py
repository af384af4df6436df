"""A ceiling on request bodies: a body over it is refused with 413 before the app sees it.

Pure ASGI, so that the limit holds for a body sent without a Content-Length (chunked) as well:
such a body is read up to the limit first, then handed on. A refused body is read to its end
(and dropped) before the 413 goes out, unless the client waits for a go-ahead to send it
(Expect: 100-continue) or it runs past DRAIN_BYTES: then the 413 goes out at once.
"""

from __future__ import annotations

import json

from starlette.types import ASGIApp, Message, Receive, Scope, Send

# A client still sending when the server closes sees a connection reset, not the 413: so a refused
# body is read first, though no more than this much of it.
DRAIN_BYTES = 64 * 2**20


class BodySizeLimit:
    def __init__(self, app: ASGIApp, max_bytes: int):
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = dict(scope["headers"])
        declared = headers.get(b"content-length")
        if declared is not None:
            if declared.isdigit() and int(declared) <= self.max_bytes:
                await self.app(scope, receive, send)  # the server delivers no more than it declared
                return
            if (
                not declared.isdigit()
                or int(declared) > DRAIN_BYTES
                or headers.get(b"expect", b"").lower() == b"100-continue"
            ):
                await self._refuse(send)  # malformed, too much to read, or not sent yet
                return
        messages, size, more = [], 0, True
        while more and size <= DRAIN_BYTES:
            message = await receive()
            size += len(message.get("body", b""))
            more = message["type"] == "http.request" and message.get("more_body", False)
            if size <= self.max_bytes:
                messages.append(message)  # kept for the app; past the limit, only counted
        if declared is not None or size > self.max_bytes:
            await self._refuse(send)
            return

        async def replay() -> Message:
            return messages.pop(0) if messages else await receive()

        await self.app(scope, replay, send)

    async def _refuse(self, send: Send) -> None:
        body = json.dumps(
            {
                "detail": [
                    {
                        "field": "body",
                        "message": (f"is larger than the limit of {self.max_bytes} bytes (PERCUSSIM_MAX_BODY_BYTES)"),
                    }
                ]
            }
        ).encode()
        await send(
            {
                "type": "http.response.start",
                "status": 413,
                "headers": [
                    (b"content-type", b"application/json"),
                    (b"content-length", str(len(body)).encode()),
                    (b"connection", b"close"),
                ],
            }
        )
        await send({"type": "http.response.body", "body": body})
