"""Optional API keys: with `PERCUSSIM_API_KEYS` set, every `/v1` call needs one in `X-API-Key`.

A key sees only the jobs and sweeps made with it. Records keep the key's id (a hash prefix),
never the key, so neither the results store nor a log holds a secret.
"""

from __future__ import annotations

import hashlib
import hmac
from typing import Annotated

from fastapi import Header, HTTPException, Request

from percussim.common.settings import Settings


def key_id(key: str) -> str:
    """What records keep of a key: enough to tell keys apart, useless to call the API with."""
    return hashlib.sha256(key.encode()).hexdigest()[:16]


def authenticate(settings: Settings):
    """A dependency that sets `request.state.owner`: the caller's key id, or None with no keys."""
    keys = settings.api_key_list()

    def check(
        request: Request,
        x_api_key: Annotated[
            str | None, Header(description="an API key, when the service is configured with PERCUSSIM_API_KEYS")
        ] = None,
    ) -> None:
        if not keys:
            request.state.owner = None
            return
        # Compared in constant time: the answer's timing must not leak a key's prefix.
        if x_api_key is None or not any(hmac.compare_digest(x_api_key.encode(), k.encode()) for k in keys):
            raise HTTPException(
                status_code=401,
                headers={"WWW-Authenticate": "X-API-Key"},
                detail="this service needs an API key in the X-API-Key header"
                + ("" if x_api_key is None else "; the one given is not known"),
            )
        request.state.owner = key_id(x_api_key)

    return check
