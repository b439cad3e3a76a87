"""
Quality of service of every formation topic, in one place.

* Commands (``cmd_vel``): reliable, keep last 10, volatile; a lost command would leave a
  robot coasting on the previous one.
* References (``/formation/reference``): reliable, keep last 10, transient local, so a node
  that joins late still gets the latest samples (and the fixed reference is never missed).
* State (``pose``, ``neighbors``): best effort, keep last 1; at 50 to 100 Hz a stale sample is
  useless and a resent one would arrive late. In lockstep the plant resends a state that was not
  answered.
* Clock (``/clock``): reliable, keep last 1; it matches rclpy's best-effort time source and
  reliable subscribers such as a recorder.
* Latched (diagnostics summaries, markers): reliable, keep last 1, transient local.
"""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

COMMAND = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                     reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE)
REFERENCE = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                       reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
STATE = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                   reliability=ReliabilityPolicy.BEST_EFFORT,
                   durability=DurabilityPolicy.VOLATILE)
CLOCK = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                   reliability=ReliabilityPolicy.RELIABLE,
                   durability=DurabilityPolicy.VOLATILE)
LATCHED = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                     reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
