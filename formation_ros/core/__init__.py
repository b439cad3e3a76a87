# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0
