#!/usr/bin/python3
"""Writes the ROS1 bag of the io tests (run with Debian's /usr/bin/python3, which has
python3-rosbag and the message packages). Every value follows a closed form that
bag_test.cc checks:

  /imu/data        sensor_msgs/Imu, 200 messages at 200 Hz from T0: w = (0.01 i, 0.02, 0.03),
                   a = (0, 0, 9.81)
  /dvl/twist       geometry_msgs/TwistWithCovarianceStamped, 20 at 20 Hz: v = (1, 0.1 i, 0)
  /dvl/twist_plain geometry_msgs/TwistStamped, 5 at 20 Hz: v = (0.5, 0, 0)
  /slam/odom       nav_msgs/Odometry, 10 at 10 Hz: p = (i, 0, 0), yaw = 0.1 i
  /slam/keyframes  geometry_msgs/PoseStamped, 3 at 1 Hz: p = (0, i, 0), identity
  /lidar/points    sensor_msgs/PointCloud2, 5 at 10 Hz, 100 points each: x = 0.01 i + k,
                   y = k, z = 1 (float32), intensity = i (float32), ring = i % 16 (uint16),
                   t = i * 1e6 ns (uint32, Ouster style)
  /cam/image       sensor_msgs/Image, 3 at 20 Hz, 4x3 bgr8, pixel (r, c) = (b=c, g=r, r=10k)
  /cam/compressed  sensor_msgs/CompressedImage, 2, an 5x2 gray PNG of value 7k
  /tf_static       tf2_msgs/TFMessage: base_link->lidar (0, 0, 0.5), lidar->lidar_optical
                   (0.1, 0, 0) rotated 90 deg about z
"""
import math
import struct
import sys
import zlib

import rosbag
import rospy
from geometry_msgs.msg import PoseStamped, TransformStamped, TwistStamped, TwistWithCovarianceStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CompressedImage, Image, Imu, PointCloud2, PointField
from tf2_msgs.msg import TFMessage

T0_NS = 1700000000 * 10**9


def stamp(ns):
    return rospy.Time(ns // 10**9, ns % 10**9)


def png_gray(width, height, value):
    raw = b"".join(b"\x00" + bytes([value]) * width for _ in range(height))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def main(path, compression="none"):
    # Small chunks: several per bag, so chunk positions and index entries are exercised.
    with rosbag.Bag(path, "w", compression=compression, chunk_threshold=8192) as bag:
        tf = TFMessage()
        for parent, child, xyz, yaw in [("base_link", "lidar", (0, 0, 0.5), 0.0),
                                        ("lidar", "lidar_optical", (0.1, 0, 0), math.pi / 2)]:
            t = TransformStamped()
            t.header.stamp = stamp(T0_NS)
            t.header.frame_id = parent
            t.child_frame_id = child
            t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
            t.transform.rotation.z = math.sin(yaw / 2)
            t.transform.rotation.w = math.cos(yaw / 2)
            tf.transforms.append(t)
        bag.write("/tf_static", tf, stamp(T0_NS))

        for i in range(200):
            ns = T0_NS + i * 5000000
            m = Imu()
            m.header.stamp = stamp(ns)
            m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = 0.01 * i, 0.02, 0.03
            m.linear_acceleration.z = 9.81
            bag.write("/imu/data", m, stamp(ns))
        for i in range(20):
            ns = T0_NS + i * 50000000
            m = TwistWithCovarianceStamped()
            m.header.stamp = stamp(ns)
            m.twist.twist.linear.x, m.twist.twist.linear.y = 1.0, 0.1 * i
            bag.write("/dvl/twist", m, stamp(ns))
        for i in range(5):
            ns = T0_NS + i * 50000000
            m = TwistStamped()
            m.header.stamp = stamp(ns)
            m.twist.linear.x = 0.5
            bag.write("/dvl/twist_plain", m, stamp(ns))
        for i in range(10):
            ns = T0_NS + i * 100000000
            m = Odometry()
            m.header.stamp = stamp(ns)
            m.pose.pose.position.x = float(i)
            m.pose.pose.orientation.z = math.sin(0.05 * i)
            m.pose.pose.orientation.w = math.cos(0.05 * i)
            bag.write("/slam/odom", m, stamp(ns))
        for i in range(3):
            ns = T0_NS + i * 1000000000
            m = PoseStamped()
            m.header.stamp = stamp(ns)
            m.pose.position.y = float(i)
            m.pose.orientation.w = 1.0
            bag.write("/slam/keyframes", m, stamp(ns))
        for k in range(5):
            ns = T0_NS + k * 100000000
            m = PointCloud2()
            m.header.stamp = stamp(ns)
            m.header.frame_id = "lidar"
            m.height, m.width = 1, 100
            m.fields = [PointField("x", 0, PointField.FLOAT32, 1), PointField("y", 4, PointField.FLOAT32, 1),
                        PointField("z", 8, PointField.FLOAT32, 1), PointField("intensity", 12, PointField.FLOAT32, 1),
                        PointField("ring", 16, PointField.UINT16, 1), PointField("t", 20, PointField.UINT32, 1)]
            m.point_step, m.row_step, m.is_bigendian, m.is_dense = 24, 2400, False, True
            m.data = b"".join(struct.pack("<ffffHxxI", 0.01 * i + k, float(k), 1.0, float(i), i % 16, i * 1000000)
                              for i in range(100))
            bag.write("/lidar/points", m, stamp(ns))
        for k in range(3):
            ns = T0_NS + k * 50000000
            m = Image()
            m.header.stamp = stamp(ns)
            m.height, m.width, m.encoding, m.step = 3, 4, "bgr8", 12
            m.data = bytes(v for r in range(3) for c in range(4) for v in (c, r, 10 * k))
            bag.write("/cam/image", m, stamp(ns))
        for k in range(2):
            ns = T0_NS + k * 50000000
            m = CompressedImage()
            m.header.stamp = stamp(ns)
            m.format = "png"
            m.data = png_gray(5, 2, 7 * k)
            bag.write("/cam/compressed", m, stamp(ns))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "none")
