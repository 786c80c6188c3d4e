"""The ROS 2 middleware of the bridge server: commands to topics, status topics back.

NOT RUN BY THE TESTS: ``rclpy`` comes with a ROS 2 installation, which cannot
be installed on the machines that build and test mcl2pnml. The code below
is a starting point to adapt to a vehicle's topics, not a tested adapter.

Each command ``{"command": "start_GoToWayPoint", "args": {...}}`` is
published as a ``std_msgs/String`` holding the JSON on ``/mcl/<command>``;
every ``std_msgs/String`` on ``/mcl/status`` is sent back as a message
(its JSON). Map your own topics by changing ``TOPIC`` and ``STATUS``, or
replace the String messages with your architecture's types.
"""
from __future__ import annotations

import json
import threading

TOPIC = "/mcl/{command}"
STATUS = "/mcl/status"


class Ros2Middleware:
    def __init__(self, reply):
        import rclpy                       # noqa: F401  (a ROS 2 installation)
        from rclpy.node import Node
        from std_msgs.msg import String

        rclpy.init()
        self.node = Node("mcl2pnml_bridge")
        self.String = String
        self.publishers = {}
        self.node.create_subscription(String, STATUS,
                                      lambda msg: reply(json.loads(msg.data)), 10)
        threading.Thread(target=rclpy.spin, args=(self.node,), daemon=True).start()

    def command(self, cmd: dict) -> None:
        topic = TOPIC.format(command=cmd["command"])
        if topic not in self.publishers:
            self.publishers[topic] = self.node.create_publisher(self.String, topic, 10)
        self.publishers[topic].publish(self.String(data=json.dumps(cmd)))
