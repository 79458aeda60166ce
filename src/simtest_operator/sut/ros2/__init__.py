"""A ROS 2 stack as the system under test: a bridge between the OSI SUT protocol and DDS.

:mod:`.bridge` is an OSI-protocol SUT towards the simulator and a DDS participant with ROS 2's
conventions towards the stack (:mod:`.interfaces`: names, types, QoS; :mod:`.dds`: Cyclone DDS
carrying ``rosbags``' CDR; :mod:`.converting`: ground truth to messages and the command back).
Needs the ``ros2`` extra (``cyclonedds``, ``rosbags``); no ROS 2 installation.
"""
