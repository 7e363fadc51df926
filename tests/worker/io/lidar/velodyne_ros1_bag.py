"""Copies a rosbag2 .db3 topic of velodyne_msgs/msg/VelodyneScan (CDR) into a ROS 1 bag of
velodyne_msgs/VelodyneScan, re-serialised by hand (no velodyne_msgs package needed).
Usage (Debian's python with python3-rosbag): velodyne_ros1_bag.py IN.db3 OUT.bag"""
import sqlite3
import struct
import sys

import rosbag
import rospy

PACKET = 1206
FULL_TEXT = """Header header
VelodynePacket[] packets

================================================================================
MSG: std_msgs/Header
uint32 seq
time stamp
string frame_id

================================================================================
MSG: velodyne_msgs/VelodynePacket
time stamp
uint8[1206] data
"""


class VelodyneScanType:
    _type = "velodyne_msgs/VelodyneScan"
    _md5sum = "50804fc9533a0e579e6322c04ae70566"
    _full_text = FULL_TEXT
    _has_header = True


def cdr_to_ros1(data):
    # CDR little endian: 4-byte encapsulation, stamp, frame_id, packets (4-aligned).
    sec, nsec = struct.unpack_from("<iI", data, 4)
    (length,) = struct.unpack_from("<I", data, 12)
    frame = data[16:16 + length - 1]
    offset = (16 + length + 3) & ~3
    (count,) = struct.unpack_from("<I", data, offset)
    offset += 4
    out = [struct.pack("<III", 0, sec, nsec), struct.pack("<I", len(frame)), frame,
           struct.pack("<I", count)]
    for _ in range(count):
        offset = (offset + 3) & ~3
        out.append(data[offset:offset + 8 + PACKET])
        offset += 8 + PACKET
    return b"".join(out), rospy.Time(sec, nsec)


def main():
    db = sqlite3.connect(sys.argv[1])
    (name,) = db.execute("select name from topics").fetchone()
    with rosbag.Bag(sys.argv[2], "w") as bag:
        for timestamp, data in db.execute("select timestamp, data from messages order by id"):
            raw, _ = cdr_to_ros1(bytes(data))
            t = rospy.Time(timestamp // 10**9, timestamp % 10**9)
            bag.write(name, (VelodyneScanType._type, raw, VelodyneScanType._md5sum, None,
                             VelodyneScanType), t, raw=True)


if __name__ == "__main__":
    main()
