#!/usr/bin/python3
"""Prints what ROS1's own python reader (Debian's python3-rosbag) reads from a bag, for
ros1_bag_reference_test.cc to compare with Keel's reader: one line per topic
  T <tab> topic <tab> type <tab> message count
then one line per message, in rosbag's time order,
  M <tab> topic <tab> sec <tab> nsec <tab> md5sum <tab> size <tab> sha256 of the bytes
Run with /usr/bin/python3 (Debian's, which has python3-rosbag)."""
import hashlib
import sys

import rosbag

with rosbag.Bag(sys.argv[1]) as bag:
    for topic, info in sorted(bag.get_type_and_topic_info().topics.items()):
        print("T\t%s\t%s\t%d" % (topic, info.msg_type, info.message_count))
    for topic, raw, t in bag.read_messages(raw=True):
        datatype, data, md5sum, position, pytype = raw
        print("M\t%s\t%d\t%d\t%s\t%d\t%s" % (topic, t.secs, t.nsecs, md5sum, len(data),
                                             hashlib.sha256(data).hexdigest()))
