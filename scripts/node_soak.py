#!/usr/bin/env python3
"""The driver of scripts/node_soak.sh: feeds a running MonoDetector node (namespace /r1, ~publish_descriptors
true) and a PlaceServer node (namespace /server, fed by the detector's place_descriptors) FRAMES images and
prints, every EVERY frames, both nodes' resident set size (/proc/<pid>/status VmRSS) and their time per frame.

One frame at a time: an image (a Gardens Point frame of data/sample, day_right then night_right cycled, as
mono8 at WIDTHxHEIGHT, stamps increasing by 0.05 s) is published and the detector's decision for it (the
`decisions` topic: one message per frame, stamped with the image's header) is awaited, so the detector never
queues and nothing is dropped. The detector's time per frame is image published -> decision received. The
place server gets a descriptor for every frame the detector stores; its time per message is descriptor
received (here) -> its decision received, and the next image waits for that decision too, so neither node
ever holds a queue: the times are processing times (plus a loopback hop). `lost` counts decisions or
descriptors that did not come within 10 s.

usage: node_soak.py FRAMES EVERY DETECTOR_PID SERVER_PID [WIDTH HEIGHT]
"""
import glob
import os
import sys
import threading
import time

import cv2
import rospy
from openable_ros.msg import LoopClosure, PlaceDescriptor
from sensor_msgs.msg import Image


NOT_STORED = ("not_keyframe", "standstill", "time_jump")  # decisions of frames the detector did not store


def rss_mb(pid):
    with open("/proc/%d/status" % pid) as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


class Soak:
    def __init__(self):
        self.lock = threading.Condition()
        self.decided = {}           # detector: stamp (ns) -> time its decision arrived
        self.status = {}            # detector: stamp (ns) -> its decision's status
        self.descriptor_seen = set()  # stamps (ns) of descriptors seen here
        self.descriptor_at = {}     # place server: stamp (ns) -> time the descriptor was seen here
        self.descriptors = 0
        self.server_decisions = 0
        self.server_ms = []         # place server latencies (ms) since the last report
        self.statuses = {}

    def on_decision(self, msg):
        now = time.perf_counter()
        with self.lock:
            self.decided[msg.header.stamp.to_nsec()] = now
            self.status[msg.header.stamp.to_nsec()] = msg.status
            self.statuses[msg.status] = self.statuses.get(msg.status, 0) + 1
            self.lock.notify_all()

    def on_descriptor(self, msg):
        with self.lock:
            self.descriptors += 1
            self.descriptor_at[msg.header.stamp.to_nsec()] = time.perf_counter()
            self.descriptor_seen.add(msg.header.stamp.to_nsec())
            self.lock.notify_all()

    def on_server_decision(self, msg):
        now = time.perf_counter()
        with self.lock:
            self.server_decisions += 1
            sent = self.descriptor_at.pop(msg.header.stamp.to_nsec(), None)
            if sent is not None:
                self.server_ms.append(1000.0 * (now - sent))
            self.lock.notify_all()


def main():
    frames, every, detector_pid, server_pid = (int(a) for a in sys.argv[1:5])
    width, height = (int(a) for a in sys.argv[5:7]) if len(sys.argv) >= 7 else (160, 90)
    rospy.init_node("node_soak", disable_signals=True)
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "sample")
    files = sorted(glob.glob(os.path.join(root, "day_right", "*.jpg"))) + sorted(
        glob.glob(os.path.join(root, "night_right", "*.jpg")))
    images = [cv2.resize(cv2.imread(f, cv2.IMREAD_GRAYSCALE), (width, height), interpolation=cv2.INTER_AREA)
              for f in files]
    soak = Soak()
    pub = rospy.Publisher("/r1/image", Image, queue_size=10)
    rospy.Subscriber("/r1/decisions", LoopClosure, soak.on_decision, queue_size=1000)
    rospy.Subscriber("/r1/place_descriptors", PlaceDescriptor, soak.on_descriptor, queue_size=1000)
    rospy.Subscriber("/server/decisions", LoopClosure, soak.on_server_decision, queue_size=1000)
    deadline = time.time() + 30.0
    while pub.get_num_connections() == 0 and time.time() < deadline:
        time.sleep(0.1)
    time.sleep(1.0)  # the subscriptions above connect too
    print("| frames | detector RSS (MB) | detector ms/frame | place server RSS (MB) | place server ms/message "
          "| descriptors | lost |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    print("| 0 | %.1f | - | %.1f | - | 0 | 0 |" % (rss_mb(detector_pid), rss_mb(server_pid)))
    sys.stdout.flush()
    lost = 0
    lost_descriptors = 0
    window = []
    msg = Image()
    msg.header.frame_id = "camera"
    msg.encoding = "mono8"
    msg.height, msg.width, msg.step = height, width, width
    start = rospy.Time(1000.0)
    for i in range(frames):
        stamp = start + rospy.Duration(0.05 * i)
        msg.header.seq = i
        msg.header.stamp = stamp
        msg.data = images[i % len(images)].tobytes()
        key = stamp.to_nsec()
        sent = time.perf_counter()
        pub.publish(msg)
        with soak.lock:
            if not soak.lock.wait_for(lambda: key in soak.decided, timeout=10.0):
                lost += 1
            else:
                window.append(1000.0 * (soak.decided.pop(key) - sent))
            status = soak.status.pop(key, None)
            if status is not None and status not in NOT_STORED:
                # A stored frame: its descriptor goes to the place server; wait for the server's decision
                # too, so that neither node ever has a queue and the times are processing times.
                if not soak.lock.wait_for(lambda: key in soak.descriptor_seen, timeout=10.0):
                    lost_descriptors += 1
                else:
                    soak.descriptor_seen.discard(key)
                    if not soak.lock.wait_for(lambda: soak.descriptors == soak.server_decisions, timeout=10.0):
                        lost_descriptors += 1
        if (i + 1) % every == 0:
            with soak.lock:
                soak.lock.wait_for(lambda: soak.descriptors == soak.server_decisions, timeout=10.0)
                server_ms = soak.server_ms
                soak.server_ms = []
                descriptors = soak.descriptors
            print("| %d | %.1f | %.2f | %.1f | %.2f | %d | %d |" % (
                i + 1, rss_mb(detector_pid), sum(window) / max(1, len(window)), rss_mb(server_pid),
                sum(server_ms) / max(1, len(server_ms)), descriptors, lost + lost_descriptors))
            sys.stdout.flush()
            window = []
    print("detector decisions by status: %s" % ", ".join("%s %d" % kv for kv in sorted(soak.statuses.items())))
    print("place server decisions: %d of %d descriptors" % (soak.server_decisions, soak.descriptors))
    return 0 if lost + lost_descriptors == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
