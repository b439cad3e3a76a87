# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The paper's maths: jump functions, the law, the moving frame, references, sensing, pairs.

The bottom room of the core: it imports no other room. The units of time and the base of the
kinds (``choice``) live here because the law's own kinds are built on them.
"""
