from mcl2pnml.runtime.simprims import SimulatedPrimitive, register


@register
class KeepDepth(SimulatedPrimitive):
    name = "KeepDepth"

    def sense(self, ctx):
        return None
