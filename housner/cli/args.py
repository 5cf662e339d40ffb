"""The command line's argument types and input checks: each refuses a bad value in one line naming the option."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import housner
from housner.effects import available_effects
from housner.engines.base import ENGINES
from housner.errors import unknown_choice

#: Exit statuses of the command (see the module docstring).
EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130
#: Exit status after SIGTERM (128 + 15), which a batch scheduler or a container runtime sends.
EXIT_TERMINATED = 143
#: ``housner run --check``: an engine's distribution verdict is FAIL.
EXIT_VERDICT = 3


class UsageError(ValueError):
    """Bad input found by the command itself (an argument, a path); exit status 2."""


class Parser(argparse.ArgumentParser):
    """argparse, with one-line errors raised as :class:`UsageError` instead of usage text and exit."""

    def error(self, message: str):  # noqa: D102 - argparse API
        raise UsageError(f"{message} (see `{self.prog} --help`)")


def _int_at_least(minimum: int, what: str):
    """An argparse type: an integer of at least ``minimum``, else "must be <what>, got ..."."""

    def parse(value: str) -> int:
        try:
            n = int(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {what}, got {value!r}") from None
        if n < minimum:
            raise argparse.ArgumentTypeError(f"must be {what}, got {value!r}")
        return n

    return parse


def folds_int(value: str) -> int:
    """``--folds``: an integer of at least 2 (an argument's type)."""
    n = nonneg_int(value)
    if n < 2:
        raise argparse.ArgumentTypeError(f"must be an integer of at least 2, got {value!r}")
    return n


def _as_float(text: str) -> float:
    """``float(text)``, NaN when it is not a number (so every range check fails on it)."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def float_within(inside, what: str):
    """An argparse type: a float for which ``inside(x)`` holds, else "must be WHAT, got 'TEXT'"."""

    def parse(value: str) -> float:
        x = _as_float(value)
        if not inside(x):
            raise argparse.ArgumentTypeError(f"must be {what}, got {value!r}")
        return x

    return parse


def amplitudes(value: str) -> tuple[float, ...]:
    """Comma-separated release amplitudes theta0/alpha, each in (0, 1) (an argument's type)."""
    out = []
    for part in value.split(","):
        a = _as_float(part)
        if not 0.0 < a < 1.0:
            raise argparse.ArgumentTypeError(
                f"must be comma-separated amplitudes theta0/alpha in (0, 1), got {part.strip()!r} in {value!r}"
            )
        out.append(a)
    return tuple(out)


def engine_name(value: str) -> str:
    """One registered engine name (an argument's type)."""
    if value not in ENGINES:
        raise argparse.ArgumentTypeError(str(unknown_choice("engine", value, ENGINES)))
    return value


def engines_arg(value: str) -> list[str]:
    """Comma-separated registered engine names, at least one (an argument's type)."""
    names = [v.strip() for v in value.split(",") if v.strip()]
    if not names:
        raise argparse.ArgumentTypeError("give at least one engine name, e.g. housner,mujoco")
    return [engine_name(n) for n in names]


def _versions() -> str:
    """``housner X (python Y; engines: ...)``: each registered engine's distribution (its spec's, else one of
    the engine's name), from package metadata (imports no engine)."""
    import platform
    from importlib.metadata import PackageNotFoundError, version

    parts = []
    for spec in ENGINES.values():
        pkg = spec.distribution or spec.name
        try:
            v = housner.__version__ if pkg == "housner" else version(pkg)
        except PackageNotFoundError:
            v = "not installed"
        parts.append(f"{spec.name} {v}")
    return f"housner {housner.__version__} (python {platform.python_version()}; engines: {', '.join(parts)})"


class VersionAction(argparse.Action):
    """``--version``: print :func:`_versions` and exit 0."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings=option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(_versions())
        parser.exit(0)


def names_arg(value: str) -> list[str]:
    """Comma-separated names, or ``none`` for an empty list (an argument's type; checked by :func:`check_effects`)."""
    if value.strip().lower() == "none":
        return []
    return [v.strip() for v in value.split(",") if v.strip()]


def check_campaign(path: str) -> None:
    """The campaign argument is a directory with campaign.toml, or a .toml file: checked before the work."""
    p = Path(path)
    if not p.exists():
        raise UsageError(f"campaign {p} does not exist (give a directory with campaign.toml, or the campaign.toml)")
    if p.is_dir() and not (p / "campaign.toml").exists():
        raise UsageError(f"campaign directory {p} holds no campaign.toml")
    if p.is_file() and p.suffix != ".toml":
        raise UsageError(f"campaign {p} is a file but not a .toml file (give the directory with campaign.toml)")
    toml = p / "campaign.toml" if p.is_dir() else p
    if toml.is_dir():
        raise UsageError(f"campaign {toml} is a directory, not a file")


def check_effects(names: list[str] | None, option: str) -> None:
    """Every name is a registered effect (plugins loaded), else one line naming ``option`` and the closest."""
    known = available_effects()
    for n in names or ():
        if n not in known:
            raise UsageError(f"argument {option}: {unknown_choice('effect', n, known)}")


def check_ensemble_option(scenario, opt: str, value) -> None:
    """``--n-motions`` and ``--seed`` apply to RDK ensembles: refused for a scenario with a fixed set of motions."""
    if value is not None and scenario.source != "rdk":
        raise UsageError(
            f"argument {opt}: scenario {scenario.name!r} has a fixed set of {scenario.n_motions} motions "
            f"(source {scenario.source!r}); {opt} applies to RDK ensembles"
        )


positive_int = _int_at_least(1, "a positive integer")
nonneg_int = _int_at_least(0, "a non-negative integer")
open_fraction = float_within(lambda x: 0.0 < x < 1.0, "a number between 0 and 1 (exclusive)")
ratio = float_within(lambda x: 0.0 < x <= 1.0, "a kinetic-energy ratio in (0, 1]")
