# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Log a condition once when it starts and once when it ends, not every cycle."""

from typing import Any, Set


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
        # rclpy ties a severity to each call site, hence one call per level.
        if level == 'error':
            self._logger.error(message)
        elif level == 'info':
            self._logger.info(message)
        else:
            self._logger.warning(message)
        return True

    def end(self, key: str, message: str = '') -> None:
        """Mark ``key`` inactive again, logging ``message`` (info) if it was active."""
        if key in self._active:
            self._active.discard(key)
            if message:
                self._logger.info(message)

    def is_active(self, key: str) -> bool:
        """Whether ``key`` is active."""
        return key in self._active
