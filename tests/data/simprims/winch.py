"""A user's simulated primitive: a winch that reels a cable in at a steady rate."""
from mcl2pnml.core.payloads import EventKind
from mcl2pnml.runtime.simprims import SimulatedPrimitive, register

RATE = 0.5      # m/s


@register
class Winch(SimulatedPrimitive):
    name, arguments = "Winch", "metres"
    achieves = "the cable is in: metres / 0.5 s after enabling"
    fails = "at once: metres not above 0"

    def check(self, ctx):
        metres = ctx.args[0] if len(ctx.args) == 1 else None
        if not isinstance(metres, (int, float)) or metres <= 0:
            return "Winch takes one length above 0"
        return None

    def sense(self, ctx):
        done = ctx.state.t >= ctx.since + ctx.args[0] / RATE - 1e-9
        return EventKind.ACHIEVED if done and ctx.goal == "C" else None
