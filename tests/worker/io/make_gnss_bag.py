"""Writes a ROS1 bag with /fix (sensor_msgs/NavSatFix) for gnss_readers_test.cc:
five messages at 1 Hz from t0 = 1700000000 s: fix i at latitude 53.5 + 1e-5 i, longitude
9.9 + 2e-5 i, altitude 40 + i; statuses 0, 1, 2, -1 (NaN position), 0; covariance types
2 (diagonal 0.25, 0.36, 1.0), 0, 3, 0, 1. Usage: make_gnss_bag.py OUT.bag"""
import math
import sys

import rosbag
import rospy
from sensor_msgs.msg import NavSatFix, NavSatStatus

statuses = [0, 1, 2, -1, 0]
cov_types = [2, 0, 3, 0, 1]
with rosbag.Bag(sys.argv[1], "w") as bag:
    for i in range(5):
        m = NavSatFix()
        t = rospy.Time(1700000000 + i, 0)
        m.header.stamp = t
        m.header.frame_id = "gnss"
        m.status.status = statuses[i]
        m.status.service = NavSatStatus.SERVICE_GPS
        no_fix = statuses[i] < 0
        m.latitude = math.nan if no_fix else 53.5 + 1e-5 * i
        m.longitude = math.nan if no_fix else 9.9 + 2e-5 * i
        m.altitude = math.nan if no_fix else 40.0 + i
        m.position_covariance = [0.25, 0, 0, 0, 0.36, 0, 0, 0, 1.0]
        m.position_covariance_type = cov_types[i]
        bag.write("/fix", m, t)
