#!/usr/bin/env python3
"""Read MCAP logs with the official Python `mcap` package (issue #27).

Usage: python3 tests/python/check_mcap.py LOG[=MESSAGES] ...

Every LOG must open, have a summary, and yield every message (with its channel and schema)
without an error; with `=MESSAGES`, exactly that many. Prints one line per log and exits
non-zero on the first failure. Needs `pip install mcap zstandard` (the logs are zstd chunks);
`tests/log_damage.rs` runs it on recovered logs when `python3 -c "import mcap"` works.
"""

import sys


def check(path, expected):
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is None:
            raise SystemExit(f"{path}: no summary")
        count = 0
        topics = set()
        for schema, channel, message in reader.iter_messages():
            if channel is None or schema is None:
                raise SystemExit(f"{path}: message {count} without channel or schema")
            topics.add(channel.topic)
            count += 1
    if expected is not None and count != expected:
        raise SystemExit(f"{path}: {count} messages, want {expected}")
    stats = summary.statistics
    if stats is not None and stats.message_count != count:
        raise SystemExit(
            f"{path}: statistics say {stats.message_count} messages, read {count}"
        )
    print(f"{path}: {count} messages on {len(topics)} channels, summary read")


def main(args):
    if not args:
        raise SystemExit(__doc__)
    for arg in args:
        path, _, expected = arg.rpartition("=") if "=" in arg else (arg, "", "")
        check(path, int(expected) if expected else None)


if __name__ == "__main__":
    main(sys.argv[1:])
