# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Exit codes that say why a process ended, in one place.

The nodes exit with them and the launcher reads them (this module imports nothing, so the
launcher's ``--help`` stays light).

0 is a normal end, 1 a failure (a node's ``finish()`` failed, a report could not be written),
2 bad parameters or usage (``formation_ros.ros.runner``, the launcher).
"""

RECORDING_FAILED = 74
"""
The recording stopped early: the recorder could not write its bag (a full disk, or any other
error on a write, flush or close). It closed the bag as it was, readable, logged one line
saying how much it holds, and ended. The launcher ends with the same code when a run's
recording stopped early. 74 is ``EX_IOERR`` of sysexits.h.
"""

ENGINE_FAILED = 70
"""
The physics engine blew up (a pose non-finite or absurd): the world stopped within the step,
logged one line naming the robot and the simulated time, and wrote what it had. 70 is
``EX_SOFTWARE`` of sysexits.h.
"""

REFUSED = 2
"""
The node refused to run here, or was given bad parameters or usage: it logged one line saying
why (another team's plant or ``/clock`` on the domain, an invalid parameter).
"""
