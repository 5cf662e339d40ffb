"""Helpers shared by several test files: motions and engine variants built for the tests."""

from __future__ import annotations

import numpy as np

from engines.mujoco_engine import MujocoEngine
from housner import GroundMotion


def windowed_sines(n: int, seed: int, *, freq=(1.0, 4.0), amp=(1.0, 4.0), scale: float = 1.0, centre=1.2, width=0.7):
    """``n`` sines [m/s^2] under a Gaussian window, 3 s at 500 Hz, named m0, m1, ...

    Frequency [Hz], amplitude (times ``scale``) and phase are drawn from
    ``default_rng(seed)``; the window is centred at ``centre`` s with half-width ``width`` s.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 3.0, 0.002)
    out = []
    for i in range(n):
        f, a, ph = rng.uniform(*freq), rng.uniform(*amp), rng.uniform(0, 2 * np.pi)
        acc = scale * a * np.sin(2 * np.pi * f * t + ph) * np.exp(-(((t - centre) / width) ** 2))
        out.append(GroundMotion(acc, 0.002, name=f"m{i}"))
    return out


class SoftGroundMujoco(MujocoEngine):
    """MuJoCo with the ground at its default solref and solimp: the first tuned contact, about 40 times too soft."""

    def mjcf(self, specimen):
        xml = super().mjcf(specimen)
        start = xml.index('<geom name="ground"')
        end = xml.index("/>", start)
        return xml[:start] + xml[start:end].split(" solref=")[0] + xml[end:]
