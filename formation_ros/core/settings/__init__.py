# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Parameters and files: declarations, typed settings, parameters files, the team's agreement.

One declaration per parameter, the guard every program reads a file through, what a team
must agree on, a robot's name and the exit codes. Imports the maths and the model.
"""
