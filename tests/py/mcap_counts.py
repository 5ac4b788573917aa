"""Lists an MCAP file's channels with the PyPI `mcap` reader (independent of
nauta's Rust reader): prints one JSON object {"channels": {topic: {"count",
"schema", "schema_encoding", "message_encoding"}}, "profile": ...}.

Used by tests/tests/recording.rs."""

import json
import sys

from mcap.reader import make_reader


def main(path):
    channels = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        for schema, channel, _message in reader.iter_messages():
            c = channels.setdefault(
                channel.topic,
                {
                    "count": 0,
                    "schema": schema.name if schema else "",
                    "schema_encoding": schema.encoding if schema else "",
                    "message_encoding": channel.message_encoding,
                },
            )
            c["count"] += 1
        summary = reader.get_summary()
        if summary is not None:
            # Channels announced without a message.
            for channel in summary.channels.values():
                schema = summary.schemas.get(channel.schema_id)
                channels.setdefault(
                    channel.topic,
                    {
                        "count": 0,
                        "schema": schema.name if schema else "",
                        "schema_encoding": schema.encoding if schema else "",
                        "message_encoding": channel.message_encoding,
                    },
                )
    print(json.dumps({"profile": header.profile, "channels": channels}))


if __name__ == "__main__":
    main(sys.argv[1])
