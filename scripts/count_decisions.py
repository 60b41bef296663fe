#!/usr/bin/env python3
"""Counts what a detector decides: every message on `decisions` by status, and the messages on
`loop_closures`, until no decision came for ~idle seconds after the first (or ~timeout passed); prints
one `status: count` line each, then `decisions: N` and `loop_closures: N`. Used by scripts/kitti_short_bag.sh.
"""
import collections
import time

import rospy
from openable_ros.msg import LoopClosure


def main():
    rospy.init_node("count_decisions")
    idle = rospy.get_param("~idle", 8.0)
    timeout = rospy.get_param("~timeout", 300.0)
    statuses = collections.Counter()
    loops = []

    def on_decision(msg):
        statuses[msg.status] += 1

    def on_loop(msg):
        loops.append((msg.query_id, msg.match_id))

    rospy.Subscriber("decisions", LoopClosure, on_decision, queue_size=1000)
    rospy.Subscriber("loop_closures", LoopClosure, on_loop, queue_size=1000)
    # Wall-clock waits: the launch runs on the bag's /clock, which stops with the bag.
    wall_start = time.time()
    wall_last = None
    seen = 0
    while not rospy.is_shutdown() and time.time() - wall_start < timeout:
        total = sum(statuses.values())
        if total != seen:
            seen, wall_last = total, time.time()
        if wall_last is not None and time.time() - wall_last > idle:
            break
        time.sleep(0.2)
    for status, count in sorted(statuses.items()):
        print(f"{status}: {count}")
    print(f"decisions: {sum(statuses.values())}")
    print(f"loop_closures: {len(loops)}" + (" " + " ".join(f"{q}-{m}" for q, m in loops) if loops else ""))


if __name__ == "__main__":
    main()
