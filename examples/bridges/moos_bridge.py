"""The MOOS-IvP middleware of the bridge server: commands posted to a MOOSDB, mail back.

NOT RUN BY THE TESTS: ``pymoos`` needs the MOOS libraries, which cannot be
installed on the machines that build and test mcl2pnml. The code below is a
starting point to adapt to a vehicle's MOOS variables, not a tested adapter.

What it trusts: every client of the MOOSDB can post ``MCL_STATUS``, and
this bridge forwards it to the mission; keep the MOOSDB's port to the
vehicle's own processes (docs/faults.md, "Trust and safety of the live link").

Each command is posted as the string variable ``MCL_<COMMAND>`` holding the
JSON (an IvP behaviour's condition can watch it, e.g. ``MCL_START_GOTOWAYPOINT``);
each change of ``MCL_STATUS`` (a JSON string the vehicle posts) is sent back
as a message.
"""
from __future__ import annotations

import json


class MoosMiddleware:
    def __init__(self, reply, host: str = "localhost", port: int = 9000):
        import pymoos                      # a MOOS installation

        self.comms = pymoos.comms()
        self.reply = reply

        def on_connect():
            return self.comms.register("MCL_STATUS", 0)

        def on_mail():
            for msg in self.comms.fetch():
                if msg.key() == "MCL_STATUS":
                    self.reply(json.loads(msg.string()))
            return True
        self.comms.set_on_connect_callback(on_connect)
        self.comms.set_on_mail_callback(on_mail)
        self.comms.run(host, port, "mcl2pnml_bridge")

    def command(self, cmd: dict) -> None:
        self.comms.notify(f"MCL_{cmd['command'].upper()}", json.dumps(cmd))

    def link_lost(self) -> None:
        """mcl2pnml is gone: ``MCL_STOP_ALL`` is the condition of the vehicle's failsafe."""
        self.comms.notify("MCL_STOP_ALL", "true")
