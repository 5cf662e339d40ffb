"""Physics engines behind one protocol: the analytic Housner model, MuJoCo and PyBullet."""

from engines.base import ENGINES, Engine, engine_class, get_engine, register_engine

__all__ = ["ENGINES", "Engine", "engine_class", "get_engine", "register_engine"]
