"""CPU profiles per thread of the running robot (``bench/run.py --profile``).

cProfile profiles only the thread that enables it, so each thread checks the window
once per wake-up: the loop after each tick (``Scheduler.add_after_tick``), the others
through one frequently called method wrapped on the *instance* (the bridge publisher's
``_states_heard``, the outbox's ``flush``, the world's ``_tick`` where rm_sim runs in the
process; the main thread checks in its spin loop). The loop's compiled modules
(rm_base/runtime/compiled.py) are invisible to cProfile: their time shows in their callers;
``RM_ROS2_COMPILED=0`` profiles them as Python. While a window is open the
wrapper enables a ``cProfile.Profile`` in its thread, and disables it when the window
closes. The timer is cProfile's default (wall clock, cheap): sleeps and waits show up as
such (``time.sleep``, lock ``acquire``, ``spin_once``) and are read past. The thread
CPU clock would hide them, but on this VM each read is a system call that made a
profiled tick ~30x slower. cProfile slows Python code down (roughly 1.5-2x); read the
profiles for where the time goes, the CPU table for how much.
"""

from __future__ import annotations

import cProfile
import io
import pstats
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any


class ThreadProfiles:
    """Per-thread cProfile instances switched on and off from the outside."""

    def __init__(self) -> None:
        self.active = False
        self._profiles: dict[int, tuple[str, cProfile.Profile, list[bool]]] = {}
        self._lock = threading.Lock()

    def check(self) -> None:
        """Call from inside a thread: start or stop its profile as the window says."""
        tid = threading.get_native_id()
        entry = self._profiles.get(tid)
        if self.active:
            if entry is None:
                profile = cProfile.Profile()
                with self._lock:
                    self._profiles[tid] = (threading.current_thread().name, profile, [True])
                profile.enable()
        elif entry is not None and entry[2][0]:
            entry[1].disable()
            entry[2][0] = False

    def wrap(self, obj: Any, attribute: str) -> None:
        """Make ``obj.attribute(...)`` call :meth:`check` first (instance attribute)."""
        original: Callable[..., Any] = getattr(obj, attribute)
        check = self.check

        def wrapped(*args: Any, **kwargs: Any) -> Any:
            check()
            return original(*args, **kwargs)

        setattr(obj, attribute, wrapped)

    def stopped(self) -> bool:
        """Whether every profile started has stopped (its thread passed a check since)."""
        with self._lock:
            return all(not running[0] for _, _, running in self._profiles.values())

    def report(self, out_dir: Path, top: int = 25) -> dict[str, Any]:
        """Write one text and one pstats profile per thread; return each thread's top functions."""
        summary: dict[str, Any] = {}
        with self._lock:
            entries = list(self._profiles.values())
        for name, profile, running in entries:
            if running[0]:
                continue  # never passed its check after the window: no clean profile
            stats = pstats.Stats(profile)
            text = io.StringIO()
            pstats.Stats(profile, stream=text).sort_stats('tottime').print_stats(top)
            safe = ''.join(c if c.isalnum() or c in '-_' else '_' for c in name)
            (out_dir / f'profile_{safe}.txt').write_text(text.getvalue())
            profile.dump_stats(out_dir / f'profile_{safe}.prof')  # for pstats / snakeviz
            rows = sorted(stats.stats.items(), key=lambda kv: kv[1][2], reverse=True)[:top]
            summary[name] = {
                'total_s': stats.total_tt,
                'top': [
                    {
                        'function': f'{Path(f[0]).name}:{f[1]}({f[2]})',
                        'ncalls': v[1],
                        'tottime_s': v[2],
                        'cumtime_s': v[3],
                    }
                    for f, v in rows
                ],
            }
        return summary
