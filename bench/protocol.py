"""The line protocol between bench/run.py and its child processes (child side).

The parent writes one command per line to the child's stdin (``<command> <args...>``); the
child answers each with one ``@@BENCH {json}`` line on stdout (other output is logged by
the parent, see :class:`bench.robot.Child`).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Mapping
from typing import Any

PREFIX = '@@BENCH '


def reply(obj: dict[str, Any]) -> None:
    """Send one reply line to the parent."""
    try:
        sys.stdout.write(PREFIX + json.dumps(obj) + '\n')
        sys.stdout.flush()
    except (BrokenPipeError, ValueError):
        pass  # the parent is gone; stdin's end of file stops this process


def serve(handlers: Mapping[str, Callable[[list[str]], dict[str, Any]]]) -> None:
    """Answer commands from stdin until ``quit`` or its end; an error is a reply too."""
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        command, args = words[0], words[1:]
        if command == 'quit':
            return
        handler = handlers.get(command)
        if handler is None:
            reply({'error': f'unknown command {command!r}'})
            continue
        try:
            reply(handler(args))
        except Exception as err:
            reply({'error': f'{type(err).__name__}: {err}'})
