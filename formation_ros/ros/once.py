# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Log a condition once when it starts and once when it ends, not every cycle."""

from typing import Any, Callable, Generic, Iterable, List, Mapping, Sequence, Set

from formation_ros.core.rules.admission import Reason, Refusals, Source
from formation_ros.core.rules.plant_status import robots_named  # noqa: F401 (its name here too)


class OnceLog:
    """Logs a condition once when it starts and once when it ends, not every cycle."""

    def __init__(self, logger: Any):
        """Log through ``logger`` (an rclpy logger)."""
        self._logger = logger
        self._active: Set[str] = set()

    def start(self, key: str, message: str, level: str = 'warning') -> bool:
        """Log ``message`` if ``key`` was not already active; return True if logged."""
        if key in self._active:
            return False
        self._active.add(key)
        self._say(message, level)
        return True

    def start_group(self, keys: Sequence[str], message: Callable[[List[str]], str],
                    level: str = 'warning') -> List[str]:
        """
        Mark ``keys`` active; log ``message(new)`` once for those that were not; return them.

        One line for every condition of a cycle that starts at once (a thousand robots' commands
        late after one stall), instead of a line each.
        """
        new = [key for key in keys if key not in self._active]
        if new:
            self._active.update(new)
            self._say(message(new), level)
        return new

    def end_group(self, keys: Sequence[str], message: Callable[[List[str]], str]) -> List[str]:
        """Mark ``keys`` inactive; log ``message(ended)`` (info) once for those active before."""
        ended = [key for key in keys if key in self._active]
        if ended:
            self._active.difference_update(ended)
            self._logger.info(message(ended))
        return ended

    def follow(self, prefix: str, present: Mapping[str, str], before: Iterable[str],
               ended: Callable[[str], str], level: str = 'error') -> None:
        """
        Log each condition of ``present`` once as it starts, and each of ``before`` that ended.

        present: {name: the line to log when it starts}; before: the names present last time,
        each gone one logged (info) as ``ended(name)``; keys are ``prefix-name``.
        """
        for name, line in present.items():
            self.start(f'{prefix}-{name}', line, level)
        for name in set(before) - set(present):
            self.end(f'{prefix}-{name}', ended(name))

    def _say(self, message: str, level: str) -> None:
        # rclpy ties a severity to each call site, hence one call per level.
        if level == 'error':
            self._logger.error(message)
        elif level == 'info':
            self._logger.info(message)
        else:
            self._logger.warning(message)

    def end(self, key: str, message: str = '') -> None:
        """Mark ``key`` inactive again, logging ``message`` (info) if it was active."""
        if key in self._active:
            self._active.discard(key)
            if message:
                self._logger.info(message)

    def is_active(self, key: str) -> bool:
        """Whether ``key`` is active."""
        return key in self._active


class RefusalLog(Generic[Source]):
    """
    Count every refused message; log each (source, reason) once while it lasts.

    The counts (:attr:`refusals`, ``core.rules.admission.Refusals``) are what a node reports and
    decides by; the log only keeps a line from repeating.
    """

    def __init__(self, once: OnceLog, line: Callable[[Source, Reason, str], str]) -> None:
        """Log through ``once``; ``line(source, reason, detail)`` is the line of a refusal."""
        self.once = once
        self.line = line
        self.refusals: Refusals[Source] = Refusals()

    @staticmethod
    def key(source: Source, reason: Reason) -> str:
        """Return the OnceLog key of refusals of ``source`` for ``reason``."""
        return f'{source}-{reason.name}'

    def refuse(self, source: Source, reason: Reason, detail: str = '', log: bool = True) -> bool:
        """Count one refusal and (with ``log``, once while it lasts) log it; return False."""
        self.refusals.add(source, reason)
        if log:
            self.once.start(self.key(source, reason), self.line(source, reason, detail), 'error')
        return False

    def admitted(self, source: Source, reason: Reason, message: str = '') -> None:
        """End the refusal of ``source`` for ``reason``, logging ``message`` if it was logged."""
        self.once.end(self.key(source, reason), message)
