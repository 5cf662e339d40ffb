"""Physics engines behind one protocol: the analytic Housner model, MuJoCo and PyBullet."""

if __name__ != "housner.engines":  # this folder imported by its 0.1 name from a checkout
    from housner._legacy import become

    become(__name__)

from housner.engines.base import ENGINES, Engine, engine_class, get_engine, register_engine

__all__ = ["ENGINES", "Engine", "engine_class", "get_engine", "register_engine"]
