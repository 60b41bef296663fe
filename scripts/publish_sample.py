#!/usr/bin/env python3
"""Publishes the bundled Gardens Point sample (data/sample: day_right, then night_right) as a live camera,
for looking at mono.launch in rviz: /camera/image_raw (bgr8, frame camera) at ~rate Hz, and tf odom -> camera
along a made-up S-shaped path (Gardens Point has no poses), the night traversal drawn ~offset metres aside
so that each loop line joins a night frame to its day twin. Used by scripts/rviz_screenshot.sh.
"""
import glob
import math
import os
import sys

import cv2
import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import Image


def path_point(i, count, offset):
    """x along the route (0.5 m a frame), y an S curve; the second traversal offset to the side."""
    x = 0.5 * i
    y = 4.0 * math.sin(2.0 * math.pi * i / count) + offset
    heading = math.atan2(4.0 * 2.0 * math.pi / count * math.cos(2.0 * math.pi * i / count), 0.5)
    return x, y, heading


def main():
    rospy.init_node("publish_sample")
    root = rospy.get_param("~sample", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "sample"))
    rate = rospy.get_param("~rate", 10.0)
    offset = rospy.get_param("~offset", 3.0)
    pub = rospy.Publisher("/camera/image_raw", Image, queue_size=400)
    tf = tf2_ros.TransformBroadcaster()
    traversals = [sorted(glob.glob(os.path.join(root, t, "*.jpg"))) for t in ("day_right", "night_right")]
    if not all(traversals):
        rospy.logfatal("no images in %s/day_right and night_right", root)
        sys.exit(1)
    deadline = rospy.Time.now() + rospy.Duration(30.0)
    while pub.get_num_connections() == 0 and rospy.Time.now() < deadline and not rospy.is_shutdown():
        rospy.sleep(0.1)
    seq = 0
    ticker = rospy.Rate(rate)
    for k, files in enumerate(traversals):
        for i, path in enumerate(files):
            if rospy.is_shutdown():
                return
            image = cv2.imread(path, cv2.IMREAD_COLOR)
            stamp = rospy.Time.now()
            x, y, heading = path_point(i, len(files), offset * k)
            t = TransformStamped()
            t.header.stamp = stamp
            t.header.frame_id = "odom"
            t.child_frame_id = "camera"
            t.transform.translation.x, t.transform.translation.y = x, y
            t.transform.rotation.z, t.transform.rotation.w = math.sin(heading / 2), math.cos(heading / 2)
            tf.sendTransform(t)
            msg = Image()
            msg.header.stamp = stamp
            msg.header.frame_id = "camera"
            msg.header.seq = seq
            msg.height, msg.width = image.shape[:2]
            msg.encoding = "bgr8"
            msg.step = image.shape[1] * 3
            msg.data = image.tobytes()
            pub.publish(msg)
            seq += 1
            ticker.sleep()
    rospy.loginfo("published %d frames", seq)


if __name__ == "__main__":
    main()
