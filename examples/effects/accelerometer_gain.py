"""A table accelerometer that reads high or low: the recorded ground_acc is a gain times the one the block felt.

The block felt ug''_recorded / gain (a transform_input effect: nothing in the kernel changes). Vertical
and other channels are left as recorded. Load with
``housner.effects.load_plugin("examples/effects/accelerometer_gain.py")``, then
``make_effect("accelerometer_gain", gain=1.12)`` for a channel that reads 12 % high.
"""

from dataclasses import dataclass, replace

from housner.effects import STAGE_GEOMETRY, Effect, param, register_effect


@register_effect
@dataclass(frozen=True)
class AccelerometerGain(Effect):
    name = "accelerometer_gain"
    stage = STAGE_GEOMETRY  # before any effect that reads the input
    gain: float = param("-", (0.8, 1.25), neutral=1.0, default=1.0, doc="recorded over felt table acceleration")

    def transform_input(self, motion):
        if self.gain == 1.0:
            return motion
        prov = f"{motion.provenance}; accelerometer gain {self.gain:g} removed".lstrip("; ")
        return replace(motion, acc=motion.acc / self.gain, provenance=prov)
