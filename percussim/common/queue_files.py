"""The embedded queue: kombu's filesystem transport, with every message written whole before a
worker can see it.

kombu's own transport opens a message's file in the queue folder and then writes it. A worker
that lists the folder in between takes the file while it is still empty: it stopped with a
`JSONDecodeError`, and the message, already removed, was lost with its job. Here a message is
written under a name the queue does not match and renamed into place when complete: a rename
within a folder is atomic, so a worker sees a whole message or none.
"""

from __future__ import annotations

import uuid
from pathlib import Path
from time import monotonic

from kombu.exceptions import ChannelError
from kombu.transport import filesystem
from kombu.utils.encoding import str_to_bytes
from kombu.utils.json import dumps

from .store import write_atomic

DRAIN_SECONDS = 0.2


class Channel(filesystem.Channel):
    def _put(self, queue, payload, **kwargs):
        """Put `payload` onto `queue`, named as kombu names it, so that messages keep their order;
        written under a temporary name ending in `.part`, which kombu's `_get` does not take (it
        takes names ending in .<queue>.msg)."""
        name = f"{int(round(monotonic() * 1000))}_{uuid.uuid4()}.{queue}.msg"
        path = Path(self.data_folder_out) / name
        try:
            write_atomic(path, str_to_bytes(dumps(payload)))
        except OSError as exc:
            raise ChannelError(f"Cannot add file {str(path)!r} to directory") from exc


class Transport(filesystem.Transport):
    Channel = Channel

    def drain_events(self, connection, timeout=None):
        """Wait for a message at most `DRAIN_SECONDS` at a time: Celery's loop for a transport that
        is polled asks for 2 s, and checks for a shutdown between waits only, so a worker took
        seconds to stop."""
        return super().drain_events(
            connection, timeout=DRAIN_SECONDS if timeout is None else min(timeout, DRAIN_SECONDS)
        )
