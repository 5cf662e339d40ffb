"""Physics engines behind one protocol: the analytic Housner model, MuJoCo and PyBullet."""

if __name__ != "housner.engines":  # this folder imported by its own name, from a checkout's root
    raise ImportError(f"`{__name__}` is not an import name of this project: import `housner.engines`")

from housner.engines.base import ENGINES, Engine, EngineSpec, engine_class, engine_spec, get_engine, register_engine

__all__ = ["ENGINES", "Engine", "EngineSpec", "engine_class", "engine_spec", "get_engine", "register_engine"]
