# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Tools that run the formation's processes: supervision and the launcher."""
