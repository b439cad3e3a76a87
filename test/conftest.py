# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Test isolation: each test run talks DDS on its own domain, on this host only."""

import os
import random

os.environ['ROS_DOMAIN_ID'] = str(random.SystemRandom().randint(1, 101))
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('MPLBACKEND', 'Agg')


def pytest_report_header(config):
    """Show the DDS domain of this run in pytest's header."""
    return f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']} (discovery: localhost only)"
