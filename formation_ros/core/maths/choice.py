# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The base of every enum of a string parameter's allowed values (``core.settings.declarations``).

Its members compare, hash, print and format as their strings, so that a value read from a
parameters file and the member it names are interchangeable as dict keys and in messages.
It has no imports of the package, so that ``core.maths.jump`` and ``core.maths.law``, which
``core.settings.declarations`` imports, can define the kinds they dispatch on.
"""

import enum


class Choice(str, enum.Enum):
    """A string parameter's allowed value: compares, prints and formats as that string."""

    def __str__(self) -> str:
        """Return the value, e.g. 'arctan'."""
        return str(self.value)

    def __format__(self, spec: str) -> str:
        """Format the value, e.g. f'{kind}' gives 'circle'."""
        return format(str(self.value), spec)
