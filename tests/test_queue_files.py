"""The embedded queue's transport: a message appears in the queue folder only whole, so that a
worker listing the folder while the API writes never takes an empty message (kombu's own
filesystem transport opens the file, then writes it; a worker that took it in between stopped
with a JSONDecodeError and the job was lost)."""

import json
import os

import pytest
from kombu import Connection

import percussim.common.queue_files as queue_files
from percussim.common.settings import Settings
from percussim.worker.app import make_app


@pytest.fixture
def connection(tmp_path):
    folder = str(tmp_path)
    with Connection(
        "filesystem://",
        transport="percussim.common.queue_files:Transport",
        transport_options={"data_folder_in": folder, "data_folder_out": folder, "control_folder": folder},
    ) as c:
        yield c


def test_a_message_is_renamed_into_the_queue_only_once_written(connection, tmp_path, monkeypatch):
    seen = []
    replace = os.replace

    def watched(source, target):
        # At the rename the queue holds no message yet, and the one to come is whole.
        seen.append(
            (
                [n for n in os.listdir(tmp_path) if n.endswith(".jobs.msg")],
                json.loads(open(source, "rb").read())["body"],
            )
        )
        replace(source, target)

    monkeypatch.setattr(os, "replace", watched)  # as common.store.write_atomic calls it
    with connection.SimpleQueue("jobs") as queue:
        queue.put({"job": "abc"})
        message = queue.get(timeout=1)
        assert message.payload == {"job": "abc"}
        message.ack()
    assert len(seen) == 1 and seen[0][0] == [] and seen[0][1]
    assert [n for n in os.listdir(tmp_path) if n.endswith((".msg", ".part"))] == []


def test_the_embedded_service_queues_through_it(tmp_path):
    app = make_app(Settings(results_dir=tmp_path, broker_url=None))
    with app.connection_for_write() as connection:
        assert connection.get_transport_cls() is queue_files.Transport
