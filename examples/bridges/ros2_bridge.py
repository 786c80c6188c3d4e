"""The ROS 2 middleware of the bridge server: commands to topics, status topics back.

NOT RUN BY THE TESTS: ``rclpy`` comes with a ROS 2 installation, which cannot
be installed on the machines that build and test mcl2pnml. The code below
is a starting point to adapt to a vehicle's topics, not a tested adapter.

Each command ``{"command": "start_GoToWayPoint", "args": {...}}`` is
published as a ``std_msgs/String`` holding the JSON on ``/mcl/<command>``;
every ``std_msgs/String`` on ``/mcl/status`` is sent back as a message
(its JSON). Map your own topics by changing ``TOPIC`` and ``STATUS``, or
replace the String messages with your architecture's types.

What it trusts, and how to close it
-----------------------------------
Plain ROS 2 (DDS) has no authentication: **anyone who can publish in the
ROS domain** (the same ``ROS_DOMAIN_ID`` on a reachable network) can
publish on ``/mcl/status``, and this bridge forwards it to the mission as
the vehicle's report (a forged ``done`` ends a task), or subscribe to the
command topics and send commands of its own to the vehicle's nodes. The
bridge's own link to mcl2pnml can be authenticated (``--secret``, TLS);
the ROS side must be closed by ROS 2 itself:

* **SROS2 / DDS Security**: ``ROS_SECURITY_ENABLE=true``,
  ``ROS_SECURITY_STRATEGY=Enforce`` and a keystore whose access-control
  permissions let only the vehicle's status node publish ``/mcl/status``
  and only this bridge publish ``/mcl/*`` commands;
* a **dedicated domain id** (``ROS_DOMAIN_ID``) and discovery kept to the
  vehicle (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``, or
  ``ROS_LOCALHOST_ONLY=1`` on older distributions), so that other machines'
  nodes do not even see the topics;
* a **sender check**: ``SENDERS`` lists the ``sender`` field values
  accepted (None: any). A field can be forged by whoever can publish, so
  this only guards against mistakes (a simulator left running in the same
  domain), not an attacker: that is what SROS2 is for.

Whatever it receives, it forwards only messages of the expected shape
(:func:`well_formed`: a JSON object of at most ``MAX_STATUS`` bytes, a
string ``message``, flat values), and publishes only commands whose name
is a valid topic name; anything else is dropped and logged.
"""
from __future__ import annotations

import json
import re
import threading

TOPIC = "/mcl/{command}"
STATUS = "/mcl/status"
#: Published (an empty JSON object) when the link to mcl2pnml is lost: the
#: vehicle's failsafe (stop every primitive, hold or surface) listens to it.
STOP_ALL = "/mcl/stop_all"
#: The ``sender`` values a status message may carry (None: any; see above).
SENDERS: frozenset[str] | None = None
#: The longest status message forwarded, in bytes.
MAX_STATUS = 4096
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def well_formed(data: str) -> dict | None:
    """The status message in ``data`` if it has the expected shape, else None."""
    if len(data.encode()) > MAX_STATUS:
        return None
    try:
        message = json.loads(data)
    except (ValueError, RecursionError):
        return None
    if not isinstance(message, dict) or not isinstance(message.get("message"), str) \
            or "link" in message:                 # the link's own lines are not the vehicle's
        return None
    if any(isinstance(v, (dict, list)) for v in message.values()):
        return None
    if SENDERS is not None and message.get("sender") not in SENDERS:
        return None
    return message


class Ros2Middleware:
    def __init__(self, reply):
        import rclpy                       # noqa: F401  (a ROS 2 installation)
        from rclpy.node import Node
        from std_msgs.msg import String

        rclpy.init()
        self.node = Node("mcl2pnml_bridge")
        self.String = String
        self.publishers = {}
        self.reply = reply
        self.node.create_subscription(String, STATUS, self.status, 10)
        threading.Thread(target=rclpy.spin, args=(self.node,), daemon=True).start()

    def status(self, msg) -> None:
        message = well_formed(msg.data)
        if message is None:
            self.node.get_logger().warning(f"dropped a status of an unexpected shape on "
                                           f"{STATUS}: {msg.data[:80]!r}")
            return
        self.reply(message)

    def publisher(self, topic: str):
        if topic not in self.publishers:
            self.publishers[topic] = self.node.create_publisher(self.String, topic, 10)
        return self.publishers[topic]

    def command(self, cmd: dict) -> None:
        name = cmd.get("command")
        if not isinstance(name, str) or not _NAME.match(name):
            raise ValueError(f"a command is named by letters, digits and _, not {name!r}")
        self.publisher(TOPIC.format(command=name)).publish(self.String(data=json.dumps(cmd)))

    def link_lost(self) -> None:
        """mcl2pnml is gone: the vehicle's failsafe takes over (see ``STOP_ALL``)."""
        self.publisher(STOP_ALL).publish(self.String(data="{}"))
